/**
 * @file mc_fake_flash.c
 * @brief Fake NOR flash with power-cut injection: see mc_fake_flash.h.
 */
#include "mc_fake_flash.h"

#include <string.h>

static bool range_ok(const mc_fake_flash_t *f, uint32_t sector, uint32_t offset, uint32_t len)
{
    return (sector < f->n_sectors) && (offset <= f->sector_bytes[sector]) &&
           (len <= f->sector_bytes[sector] - offset);
}

/* One step: true if it may happen in full; *p_torn when it is the cut one. */
static bool step(mc_fake_flash_t *f, bool *p_torn)
{
    *p_torn = false;
    f->steps++;
    if ((f->cut_step != 0u) && (f->steps >= f->cut_step)) {
        f->dead = true;
        *p_torn = (f->tear == MC_FAKE_FLASH_TEAR_HALF);
        return false;
    }
    return true;
}

static int op_sector_size(void *ctx, uint32_t sector, uint32_t *p_bytes)
{
    const mc_fake_flash_t *f = (const mc_fake_flash_t *)ctx;
    if (sector >= f->n_sectors) {
        return -EINVAL;
    }
    *p_bytes = f->sector_bytes[sector];
    return 0;
}

static int op_erase(void *ctx, uint32_t sector)
{
    mc_fake_flash_t *f = (mc_fake_flash_t *)ctx;
    bool torn = false;
    if (f->dead) {
        return -EIO;
    }
    if (sector >= f->n_sectors) {
        return -EINVAL;
    }
    if (f->fail_next != 0) {
        const int e = f->fail_next;
        f->fail_next = 0;
        return e;
    }
    uint8_t *p = f->mem + f->sector_start[sector];
    if (!step(f, &torn)) {
        if (torn) {
            (void)memset(p, 0xFF, f->sector_bytes[sector] / 2u);
        }
        return -EIO;
    }
    (void)memset(p, 0xFF, f->sector_bytes[sector]);
    f->erases++;
    return 0;
}

static int op_program(void *ctx, uint32_t sector, uint32_t offset, const uint32_t *p_words,
                      uint32_t n_words)
{
    mc_fake_flash_t *f = (mc_fake_flash_t *)ctx;
    if (f->dead) {
        return -EIO;
    }
    if (((offset % MC_HAL_FLASH_WORD_BYTES) != 0u) || (n_words > (0xFFFFFFFFu / 4u)) ||
        !range_ok(f, sector, offset, n_words * MC_HAL_FLASH_WORD_BYTES)) {
        return -EINVAL;
    }
    if (f->fail_next != 0) {
        const int e = f->fail_next;
        f->fail_next = 0;
        return e;
    }
    for (uint32_t i = 0u; i < n_words; ++i) {
        uint8_t *p = f->mem + f->sector_start[sector] + offset + (size_t)4u * i;
        uint32_t w;
        bool torn = false;
        (void)memcpy(&w, p, sizeof w);
        if (!step(f, &torn)) {
            if (torn) {
                w &= p_words[i] | 0xFFFF0000u; /* only the low half's bits cleared */
                (void)memcpy(p, &w, sizeof w);
            }
            return -EIO;
        }
        w &= p_words[i];
        (void)memcpy(p, &w, sizeof w);
        f->words++;
    }
    return 0;
}

static int op_read(void *ctx, uint32_t sector, uint32_t offset, void *p_buf, uint32_t len)
{
    const mc_fake_flash_t *f = (const mc_fake_flash_t *)ctx;
    if (f->dead) {
        return -EIO;
    }
    if (!range_ok(f, sector, offset, len)) {
        return -EINVAL;
    }
    (void)memcpy(p_buf, f->mem + f->sector_start[sector] + offset, len);
    return 0;
}

static const mc_hal_flash_ops_t fake_flash_ops = {
    .sector_size = op_sector_size,
    .erase = op_erase,
    .program = op_program,
    .read = op_read,
};

int mc_fake_flash_init(mc_fake_flash_t *f, uint8_t *mem, const uint32_t *sector_bytes,
                       uint32_t n_sectors)
{
    uint32_t start = 0u;
    if ((f == NULL) || (mem == NULL) || (sector_bytes == NULL) || (n_sectors == 0u) ||
        (n_sectors > MC_FAKE_FLASH_MAX_SECTORS)) {
        return -EINVAL;
    }
    for (uint32_t i = 0u; i < n_sectors; ++i) {
        if ((sector_bytes[i] == 0u) || ((sector_bytes[i] % MC_HAL_FLASH_WORD_BYTES) != 0u)) {
            return -EINVAL;
        }
    }
    (void)memset(f, 0, sizeof *f);
    for (uint32_t i = 0u; i < n_sectors; ++i) {
        f->sector_bytes[i] = sector_bytes[i];
        f->sector_start[i] = start;
        start += sector_bytes[i];
    }
    f->mem = mem;
    f->n_sectors = n_sectors;
    f->dev.ops = &fake_flash_ops;
    f->dev.ctx = f;
    return 0;
}

void mc_fake_flash_cut_at(mc_fake_flash_t *f, uint32_t k, mc_fake_flash_tear_t tear)
{
    f->cut_step = (k == 0u) ? 0u : f->steps + k;
    f->tear = tear;
}
