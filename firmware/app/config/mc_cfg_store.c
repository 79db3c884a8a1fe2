/**
 * @file mc_cfg_store.c
 * @brief A/B configuration store: see mc_cfg_store.h.
 */
#include "mc_cfg_store.h"

#include <stddef.h>

#include "mc_crc32.h"

#define W MC_HAL_FLASH_WORD_BYTES

int mc_cfg_store_init(mc_cfg_store_t *s, const mc_cfg_store_cfg_t *cfg)
{
    uint32_t bytes[2] = {0u, 0u};
    if ((s == NULL) || (cfg == NULL) || (cfg->flash == NULL) ||
        (cfg->sector[0] == cfg->sector[1])) {
        return -EINVAL;
    }
    for (uint32_t i = 0u; i < 2u; ++i) {
        if ((mc_hal_flash_sector_size(cfg->flash, cfg->sector[i], &bytes[i]) != 0) ||
            (bytes[i] < MC_CFG_REC_WORDS * W)) {
            return -EINVAL;
        }
    }
    {
        const mc_cfg_store_t z = {0};
        *s = z;
    }
    s->cfg = *cfg;
    s->sector_bytes[0] = bytes[0];
    s->sector_bytes[1] = bytes[1];
    s->active = -1;
    s->append_off[0] = MC_CFG_OFF_NONE;
    s->append_off[1] = MC_CFG_OFF_NONE;
    s->boot = MC_CFG_BOOT_EMPTY;
    return 0;
}

static int read_word(const mc_cfg_store_t *s, uint32_t i, uint32_t off, uint32_t *p_w)
{
    return mc_hal_flash_read(s->cfg.flash, s->cfg.sector[i], off, p_w, W);
}

/* A valid record at off of sector i? Returns 0 and its length in words,
 * -EAGAIN (not a record), -EIO (read failed). */
static int check_record(const mc_cfg_store_t *s, uint32_t i, uint32_t off, uint32_t *p_words,
                        uint32_t hdr[MC_CFG_HDR_WORDS])
{
    uint32_t crc = MC_CRC32_INIT;
    uint32_t stored = 0u;
    uint32_t n;
    uint32_t words;
    if ((off > s->sector_bytes[i]) || (s->sector_bytes[i] - off < MC_CFG_HDR_WORDS * W) ||
        (mc_hal_flash_read(s->cfg.flash, s->cfg.sector[i], off, hdr, MC_CFG_HDR_WORDS * W) != 0)) {
        return (off > s->sector_bytes[i] || s->sector_bytes[i] - off < MC_CFG_HDR_WORDS * W)
                   ? -EAGAIN
                   : -EIO;
    }
    n = hdr[3] & 0xFFFFu;
    if ((hdr[0] != MC_CFG_MAGIC) || ((hdr[3] >> 16) != 0xFFFFu) || (n > MC_CFG_ENTRIES_MAX)) {
        return -EAGAIN;
    }
    words = MC_CFG_HDR_WORDS + 2u * n + 1u;
    if (words * W > s->sector_bytes[i] - off) {
        return -EAGAIN;
    }
    crc = mc_crc32_update(crc, hdr, (size_t)MC_CFG_HDR_WORDS * W);
    for (uint32_t k = MC_CFG_HDR_WORDS; k + 1u < words; ++k) {
        uint32_t w;
        if (read_word(s, i, off + k * W, &w) != 0) {
            return -EIO;
        }
        crc = mc_crc32_update(crc, &w, W);
    }
    if (read_word(s, i, off + (words - 1u) * W, &stored) != 0) {
        return -EIO;
    }
    if (mc_crc32_final(crc) != stored) {
        return -EAGAIN;
    }
    *p_words = words;
    return 0;
}

/* Walk sector i's records; returns 0 or -EIO. *p_any: not erased at 0. */
static int scan_sector(mc_cfg_store_t *s, uint32_t i, bool *p_any)
{
    uint32_t off = 0u;
    s->append_off[i] = MC_CFG_OFF_NONE;
    while (off + W <= s->sector_bytes[i]) {
        uint32_t hdr[MC_CFG_HDR_WORDS];
        uint32_t words = 0u;
        uint32_t w;
        int rc;
        if (read_word(s, i, off, &w) != 0) {
            return -EIO;
        }
        if (w == MC_HAL_FLASH_ERASED_WORD) {
            s->append_off[i] = off;
            return 0;
        }
        *p_any = true;
        rc = check_record(s, i, off, &words, hdr);
        if (rc == -EIO) {
            return rc;
        }
        if (rc != 0) {
            return 0; /* a cut record: the rest of the sector is unusable */
        }
        if ((s->active < 0) || mc_cfg_store_seq_newer(hdr[2], s->seq)) {
            s->seq = hdr[2];
            s->active = (int32_t)i;
            s->newest_off = off;
        }
        off += words * W;
    }
    return 0; /* full */
}

static int scan(mc_cfg_store_t *s, bool *p_any)
{
    s->active = -1;
    s->seq = 0u;
    s->newest_off = 0u;
    *p_any = false;
    for (uint32_t i = 0u; i < 2u; ++i) {
        if (scan_sector(s, i, p_any) != 0) {
            return -EIO;
        }
    }
    s->scanned = true;
    return 0;
}

/* Decode the newest record into *p (defaults first). */
static mc_cfg_boot_t decode(mc_cfg_store_t *s, mc_params_t *p)
{
    const uint32_t i = (uint32_t)s->active;
    uint32_t hdr[MC_CFG_HDR_WORDS];
    uint32_t words = 0u;
    uint32_t n;
    uint32_t set = 0u;
    if (check_record(s, i, s->newest_off, &words, hdr) != 0) {
        return MC_CFG_BOOT_FLASH; /* valid during the scan, not now: the flash is failing */
    }
    if (((hdr[1] & 0xFFFFu) != MC_CFG_FORMAT) || ((hdr[1] >> 16) != MC_PARAMS_LAYOUT_VERSION)) {
        /* No migration from another layout version is known to this
         * firmware (layout 1 is the first): refuse rather than guess. */
        return MC_CFG_BOOT_LAYOUT;
    }
    *p = mc_params_default;
    n = hdr[3] & 0xFFFFu;
    for (uint32_t k = 0u; k < n; ++k) {
        uint32_t e[2];
        const mc_param_info_t *info;
        if (mc_hal_flash_read(s->cfg.flash, s->cfg.sector[i],
                              s->newest_off + (MC_CFG_HDR_WORDS + 2u * k) * W, e, 2u * W) != 0) {
            return MC_CFG_BOOT_FLASH;
        }
        info = mc_param_find(e[0], NULL);
        if ((info == NULL) || (info->offset == MC_PARAM_NO_FIELD)) {
            s->boot_dropped++; /* removed since, or never stored */
            continue;
        }
        if (mc_param_check_value(info, e[1]) != MC_PARAM_OK) {
            return MC_CFG_BOOT_INVALID; /* the range narrowed since */
        }
        mc_param_set_raw(p, info, e[1]);
        set++;
    }
    if (mc_params_validate(p) != MC_PARAMS_OK) {
        return MC_CFG_BOOT_INVALID;
    }
    s->boot_missing = (set < MC_PARAM_STORED_COUNT) ? MC_PARAM_STORED_COUNT - set : 0u;
    return ((s->boot_dropped == 0u) && (s->boot_missing == 0u)) ? MC_CFG_BOOT_STORED
                                                                : MC_CFG_BOOT_MIGRATED;
}

mc_cfg_boot_t mc_cfg_store_load(mc_cfg_store_t *s, mc_params_t *p_out)
{
    bool any = false;
    mc_cfg_boot_t st;
    if ((s == NULL) || (p_out == NULL)) {
        return MC_CFG_BOOT_FLASH;
    }
    s->boot_dropped = 0u;
    s->boot_missing = 0u;
    if (scan(s, &any) != 0) {
        st = MC_CFG_BOOT_FLASH;
    } else if (s->active < 0) {
        st = any ? MC_CFG_BOOT_CORRUPT : MC_CFG_BOOT_EMPTY;
    } else {
        mc_params_t p;
        st = decode(s, &p);
        if ((st == MC_CFG_BOOT_STORED) || (st == MC_CFG_BOOT_MIGRATED)) {
            *p_out = p;
        }
    }
    if ((st != MC_CFG_BOOT_STORED) && (st != MC_CFG_BOOT_MIGRATED)) {
        *p_out = mc_params_default;
    }
    s->boot = st;
    return st;
}

int mc_cfg_store_find_raw(mc_cfg_store_t *s, uint32_t id, uint32_t *p_raw)
{
    bool any = false;
    uint32_t hdr[MC_CFG_HDR_WORDS];
    uint32_t words = 0u;
    uint32_t i;
    if ((s == NULL) || (p_raw == NULL)) {
        return -EINVAL;
    }
    if (scan(s, &any) != 0) {
        return -EIO;
    }
    if (s->active < 0) {
        return -ENOENT;
    }
    i = (uint32_t)s->active;
    if (check_record(s, i, s->newest_off, &words, hdr) != 0) {
        return -EIO; /* valid during the scan, not now */
    }
    if ((hdr[1] & 0xFFFFu) != MC_CFG_FORMAT) {
        return -ENOENT;
    }
    for (uint32_t k = 0u; k < (hdr[3] & 0xFFFFu); ++k) {
        uint32_t e[2];
        if (mc_hal_flash_read(s->cfg.flash, s->cfg.sector[i],
                              s->newest_off + (MC_CFG_HDR_WORDS + 2u * k) * W, e, 2u * W) != 0) {
            return -EIO;
        }
        if (e[0] == id) {
            *p_raw = e[1];
            return 0;
        }
    }
    return -ENOENT;
}

/* [off, off + bytes) of sector i reads erased. */
static bool region_erased(const mc_cfg_store_t *s, uint32_t i, uint32_t off, uint32_t bytes)
{
    if ((off == MC_CFG_OFF_NONE) || (off > s->sector_bytes[i]) ||
        (bytes > s->sector_bytes[i] - off)) {
        return false;
    }
    for (uint32_t k = 0u; k < bytes; k += W) {
        uint32_t w;
        if ((read_word(s, i, off + k, &w) != 0) || (w != MC_HAL_FLASH_ERASED_WORD)) {
            return false;
        }
    }
    return true;
}

uint32_t mc_cfg_store_seq_next(uint32_t seq)
{
    return (seq == 0xFFFFFFFFu) ? 1u : seq + 1u;
}

bool mc_cfg_store_seq_newer(uint32_t a, uint32_t b)
{
    return (int32_t)(a - b) > 0;
}

/* s->rec: the record of p with sequence number seq (CRC included). */
static void build_record(mc_cfg_store_t *s, const mc_params_t *p, uint32_t seq)
{
    uint32_t k = 0u;
    s->rec[k++] = MC_CFG_MAGIC;
    s->rec[k++] = MC_CFG_FORMAT | ((uint32_t)MC_PARAMS_LAYOUT_VERSION << 16);
    s->rec[k++] = seq;
    s->rec[k++] = MC_PARAM_STORED_COUNT | 0xFFFF0000u;
    for (uint32_t i = 0u; i < MC_PARAM_COUNT; ++i) {
        const mc_param_info_t *info = &mc_param_table[i];
        if (info->offset != MC_PARAM_NO_FIELD) {
            s->rec[k++] = info->id;
            s->rec[k++] = mc_param_get_raw(p, info);
        }
    }
    s->rec[k] = mc_crc32(s->rec, (size_t)k * W);
}

static int scan_once(mc_cfg_store_t *s)
{
    bool any = false;
    if (s->scanned) {
        return 0;
    }
    return scan(s, &any);
}

bool mc_cfg_store_holds(mc_cfg_store_t *s, const mc_params_t *p)
{
    uint32_t words = 0u;
    uint32_t hdr[MC_CFG_HDR_WORDS];
    if ((s == NULL) || (p == NULL) || (scan_once(s) != 0) || (s->active < 0)) {
        return false;
    }
    /* the newest record is valid (checked again: the flash may have failed
     * since the scan) and as long as ours */
    if ((check_record(s, (uint32_t)s->active, s->newest_off, &words, hdr) != 0) ||
        (words != MC_CFG_REC_WORDS)) {
        return false;
    }
    build_record(s, p, hdr[2]);
    for (uint32_t k = 0u; k + 1u < MC_CFG_REC_WORDS; ++k) {
        uint32_t w;
        if ((read_word(s, (uint32_t)s->active, s->newest_off + k * W, &w) != 0) ||
            (w != s->rec[k])) {
            return false;
        }
    }
    return true;
}

int mc_cfg_store_save(mc_cfg_store_t *s, const mc_params_t *p)
{
    const uint32_t bytes = MC_CFG_REC_WORDS * W;
    uint32_t target;
    uint32_t off;
    uint32_t words = 0u;
    uint32_t hdr[MC_CFG_HDR_WORDS];
    if ((s == NULL) || (p == NULL) || (mc_params_validate(p) != MC_PARAMS_OK)) {
        return -EINVAL;
    }
    if (scan_once(s) != 0) {
        return -EIO;
    }
    build_record(s, p, mc_cfg_store_seq_next(s->seq));

    target = (s->active >= 0) ? (uint32_t)s->active : 0u;
    off = s->append_off[target];
    if (!region_erased(s, target, off, bytes)) {
        /* The sector of the newest record is full (or cut): start the
         * other one. It holds only older records. */
        target ^= 1u;
        off = 0u;
        s->append_off[target] = MC_CFG_OFF_NONE;
        if (mc_hal_flash_erase(s->cfg.flash, s->cfg.sector[target]) != 0) {
            return -EIO;
        }
    }
    if ((mc_hal_flash_program(s->cfg.flash, s->cfg.sector[target], off, s->rec, MC_CFG_REC_WORDS) !=
         0) ||
        (check_record(s, target, off, &words, hdr) != 0) || (words != MC_CFG_REC_WORDS) ||
        (hdr[2] != s->rec[2])) {
        s->append_off[target] = MC_CFG_OFF_NONE; /* not again before an erase */
        return -EIO;
    }
    s->seq = s->rec[2];
    s->active = (int32_t)target;
    s->newest_off = off;
    s->append_off[target] = off + bytes;
    s->saves++;
    return 0;
}
