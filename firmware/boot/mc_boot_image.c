/**
 * @file mc_boot_image.c
 * @brief The application image and its check: see mc_boot_image.h.
 */
#include "mc_boot_image.h"

#include "mc_boot_layout.h"
#include "mc_crc32.h"

/* Bytes read per flash call while computing a CRC (stack buffer). */
#define CHUNK_BYTES 128u

void mc_boot_crc_table_init(mc_boot_crc_table_t *tab)
{
    /* The table entry of byte b is the bitwise CRC register after b alone,
     * from a zero register: the same polynomial by construction. */
    for (uint32_t b = 0u; b < 256u; ++b) {
        const uint8_t byte = (uint8_t)b;
        tab->t[b] = mc_crc32_update(0u, &byte, 1u);
    }
}

uint32_t mc_boot_crc32_update(const mc_boot_crc_table_t *tab, uint32_t state, const void *data,
                              size_t len)
{
    const uint8_t *p = (const uint8_t *)data;
    uint32_t c = state;
    if (tab == NULL) {
        return mc_crc32_update(state, data, len);
    }
    for (size_t i = 0u; i < len; ++i) {
        c = tab->t[(c ^ (uint32_t)p[i]) & 0xFFu] ^ (c >> 8);
    }
    return c;
}

mc_boot_slot_t mc_boot_slot_layout1(const mc_hal_flash_t *flash, uint32_t board_id,
                                    const mc_boot_crc_table_t *crc)
{
    mc_boot_slot_t s;
    s.flash = flash;
    s.first_sector = MC_BOOT_APP_FIRST_SECTOR;
    s.n_sectors = MC_BOOT_APP_SECTORS;
    s.addr = MC_BOOT_APP_ADDR;
    s.ram_start = MC_BOOT_RAM_START;
    s.ram_end = MC_BOOT_RAM_END;
    s.board_id = board_id;
    s.layout_id = MC_BOOT_LAYOUT_ID;
    s.crc_table = crc;
    return s;
}

uint32_t mc_boot_slot_bytes(const mc_boot_slot_t *s)
{
    uint32_t total = 0u;
    if ((s == NULL) || (s->flash == NULL) || (s->n_sectors == 0u) ||
        (s->n_sectors > MC_BOOT_SLOT_SECTORS_MAX)) {
        return 0u;
    }
    for (uint32_t i = 0u; i < s->n_sectors; ++i) {
        uint32_t b = 0u;
        if ((mc_hal_flash_sector_size(s->flash, s->first_sector + i, &b) != 0) ||
            (b > 0xFFFFFFFFu - total)) {
            return 0u;
        }
        total += b;
    }
    return total;
}

bool mc_boot_slot_locate(const mc_boot_slot_t *s, uint32_t off, uint32_t *p_sector,
                         uint32_t *p_sector_off, uint32_t *p_room)
{
    uint32_t start = 0u;
    if ((s == NULL) || (s->n_sectors > MC_BOOT_SLOT_SECTORS_MAX)) {
        return false;
    }
    for (uint32_t i = 0u; i < s->n_sectors; ++i) {
        uint32_t b = 0u;
        if (mc_hal_flash_sector_size(s->flash, s->first_sector + i, &b) != 0) {
            return false;
        }
        if (off - start < b) {
            *p_sector = s->first_sector + i;
            *p_sector_off = off - start;
            *p_room = b - (off - start);
            return true;
        }
        start += b;
    }
    return false;
}

int mc_boot_slot_read(const mc_boot_slot_t *s, uint32_t off, void *p_buf, uint32_t len)
{
    uint8_t *out = (uint8_t *)p_buf;
    while (len > 0u) {
        uint32_t sector = 0u;
        uint32_t sector_off = 0u;
        uint32_t room = 0u;
        if (!mc_boot_slot_locate(s, off, &sector, &sector_off, &room)) {
            return -EINVAL;
        }
        const uint32_t n = (len < room) ? len : room;
        const int rc = mc_hal_flash_read(s->flash, sector, sector_off, out, n);
        if (rc != 0) {
            return rc;
        }
        out += n;
        off += n;
        len -= n;
    }
    return 0;
}

/* CRC state continued over [from, to) of the slot. */
static int crc_range(const mc_boot_slot_t *s, uint32_t from, uint32_t to, uint32_t *p_state)
{
    uint8_t buf[CHUNK_BYTES];
    uint32_t off = from;
    while (off < to) {
        const uint32_t n = ((to - off) < CHUNK_BYTES) ? (to - off) : CHUNK_BYTES;
        const int rc = mc_boot_slot_read(s, off, buf, n);
        if (rc != 0) {
            return rc;
        }
        *p_state = mc_boot_crc32_update(s->crc_table, *p_state, buf, n);
        off += n;
    }
    return 0;
}

int mc_boot_slot_crc(const mc_boot_slot_t *s, uint32_t image_bytes, uint32_t *p_crc)
{
    uint32_t c = MC_CRC32_INIT;
    int rc;
    if ((s == NULL) || (p_crc == NULL) || (image_bytes < MC_BOOT_IMAGE_MIN_BYTES)) {
        return -EINVAL;
    }
    rc = crc_range(s, 0u, MC_BOOT_CRC_WORD_OFFSET, &c);
    if (rc == 0) {
        rc = crc_range(s, MC_BOOT_IMAGE_MIN_BYTES, image_bytes, &c);
    }
    if (rc == 0) {
        *p_crc = mc_crc32_final(c);
    }
    return rc;
}

mc_boot_img_t mc_boot_image_check_hdr(const mc_boot_slot_t *s, const mc_boot_image_hdr_t *h)
{
    if (h->magic == MC_HAL_FLASH_ERASED_WORD) {
        return MC_BOOT_IMG_EMPTY;
    }
    if (h->magic != MC_BOOT_IMAGE_MAGIC) {
        return MC_BOOT_IMG_MAGIC;
    }
    if (h->hdr_version != MC_BOOT_HDR_VERSION) {
        return MC_BOOT_IMG_HDR_VERSION;
    }
    if (h->board_id != s->board_id) {
        return MC_BOOT_IMG_BOARD;
    }
    if (h->layout_id != s->layout_id) {
        return MC_BOOT_IMG_LAYOUT;
    }
    if (((h->image_bytes % 4u) != 0u) || (h->image_bytes < MC_BOOT_IMAGE_MIN_BYTES) ||
        (h->image_bytes > mc_boot_slot_bytes(s))) {
        return MC_BOOT_IMG_SIZE;
    }
    return MC_BOOT_IMG_OK;
}

/* Initial SP in RAM (word aligned), reset handler Thumb and in the image. */
static bool vectors_ok(const mc_boot_slot_t *s, const uint32_t vec[2], uint32_t image_bytes)
{
    const uint32_t pc = vec[1] & ~1u;
    return (vec[0] >= s->ram_start) && (vec[0] <= s->ram_end) && ((vec[0] & 3u) == 0u) &&
           ((vec[1] & 1u) != 0u) && (pc >= s->addr) && (pc - s->addr < image_bytes);
}

mc_boot_img_t mc_boot_image_check(const mc_boot_slot_t *s, mc_boot_image_hdr_t *p_hdr)
{
    mc_boot_image_hdr_t h = {0};
    uint32_t crc = 0u;
    mc_boot_img_t r;
    if ((s == NULL) || (mc_boot_slot_bytes(s) < MC_BOOT_IMAGE_MIN_BYTES)) {
        return MC_BOOT_IMG_FLASH;
    }
    if (mc_boot_slot_read(s, MC_BOOT_HDR_OFFSET, &h, MC_BOOT_HDR_BYTES) != 0) {
        const mc_boot_image_hdr_t z = {0};
        h = z;
        r = MC_BOOT_IMG_FLASH;
    } else {
        r = mc_boot_image_check_hdr(s, &h);
    }
    if (r == MC_BOOT_IMG_OK) {
        uint32_t vec[2] = {0u, 0u};
        const bool read_ok = (mc_boot_slot_crc(s, h.image_bytes, &crc) == 0) &&
                             (mc_boot_slot_read(s, 0u, vec, sizeof vec) == 0);
        if (!read_ok) {
            r = MC_BOOT_IMG_FLASH;
        } else if (crc != h.crc32) {
            r = MC_BOOT_IMG_CRC;
        } else if (h.commit != MC_BOOT_COMMIT_MAGIC) {
            r = MC_BOOT_IMG_UNCOMMITTED;
        } else if (!vectors_ok(s, vec, h.image_bytes)) {
            r = MC_BOOT_IMG_VECTORS;
        } else {
            r = MC_BOOT_IMG_OK;
        }
    }
    if (p_hdr != NULL) {
        *p_hdr = h;
    }
    return r;
}
