/**
 * @file mc_cfg_store.c
 * @brief A/B configuration store: see mc_cfg_store.h.
 */
#include "mc_cfg_store.h"

#include <stddef.h>
#include <string.h>

#include "mc_crc32.h"

#define W MC_HAL_FLASH_WORD_BYTES

static void sync_own(mc_cfg_store_t *s);

int mc_cfg_store_init(mc_cfg_store_t *s, const mc_cfg_store_cfg_t *cfg)
{
    uint32_t bytes[2] = {0u, 0u};
    if ((s == NULL) || (cfg == NULL) || (cfg->flash == NULL) ||
        (cfg->sector[0] == cfg->sector[1]) || (cfg->axis >= MC_CFG_AXES)) {
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
    s->home = -1;
    for (uint32_t k = 0u; k < MC_CFG_KINDS; ++k) {
        s->kind_sec[k] = -1;
    }
    sync_own(s);
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
    /* any kind (magic) in the envelope: one this image does not know is
     * skipped by its length, not taken for a cut record (scan_sector) */
    if ((hdr[0] == MC_HAL_FLASH_ERASED_WORD) || ((hdr[3] >> 16) != 0xFFFFu) ||
        (n > MC_CFG_ENTRIES_MAX)) {
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

/* Record kinds: kind k belongs to axis k / 2 and is its configuration (k
 * even) or its anticogging map (k odd); mc_cfg_store.h, "Axes". */
static const uint32_t k_magic[MC_CFG_KINDS] = {MC_CFG_MAGIC, MC_CFG_MAP_MAGIC, MC_CFG_MAGIC_AX1,
                                               MC_CFG_MAP_MAGIC_AX1};

/* The kind of a magic, MC_CFG_KINDS for one this image does not know. */
static uint32_t kind_of(uint32_t magic)
{
    uint32_t k = 0u;
    while ((k < MC_CFG_KINDS) && (k_magic[k] != magic)) {
        ++k;
    }
    return k;
}

static uint32_t own_cfg(const mc_cfg_store_t *s)
{
    return 2u * s->cfg.axis;
}

static uint32_t own_map(const mc_cfg_store_t *s)
{
    return (2u * s->cfg.axis) + 1u;
}

/* The own axis's view (active, seq, newest_off, map_sec, map_off) of the
 * per-kind locations. */
static void sync_own(mc_cfg_store_t *s)
{
    const uint32_t c = own_cfg(s);
    const uint32_t m = own_map(s);
    s->active = s->kind_sec[c];
    s->newest_off = s->kind_off[c];
    s->seq = (s->kind_sec[c] >= 0) ? s->kind_seq[c] : 0u;
    s->map_sec = s->kind_sec[m];
    s->map_off = s->kind_off[m];
}

/* The newest record of one kind in one sector. */
typedef struct {
    bool have;
    uint32_t seq;
    uint32_t off;
} kind_loc_t;

/* Walk sector i's records, the newest of each kind into loc; returns 0 or
 * -EIO. *p_any: something other than erased words and valid records of
 * other kinds than this axis's configuration. */
static int scan_sector(mc_cfg_store_t *s, uint32_t i, bool *p_any, kind_loc_t loc[MC_CFG_KINDS])
{
    uint32_t off = 0u;
    s->append_off[i] = MC_CFG_OFF_NONE;
    while (off + W <= s->sector_bytes[i]) {
        uint32_t hdr[MC_CFG_HDR_WORDS];
        uint32_t words = 0u;
        uint32_t w;
        uint32_t k;
        int rc;
        if (read_word(s, i, off, &w) != 0) {
            return -EIO;
        }
        if (w == MC_HAL_FLASH_ERASED_WORD) {
            s->append_off[i] = off;
            return 0;
        }
        rc = check_record(s, i, off, &words, hdr);
        if (rc == -EIO) {
            return rc;
        }
        /* not erased and not a valid record: a configuration once written
         * (valid or not: no configuration record then boots CORRUPT, not
         * EMPTY) */
        if (rc != 0) {
            *p_any = true;
            return 0; /* a cut record: the rest of the sector is unusable */
        }
        k = kind_of(hdr[0]);
        if (k == MC_CFG_KINDS) {
            off += words * W; /* a kind of a later image: skipped whole */
            continue;
        }
        *p_any = *p_any || (k == own_cfg(s));
        if (!loc[k].have || mc_cfg_store_seq_newer(hdr[2], loc[k].seq)) {
            loc[k].have = true;
            loc[k].seq = hdr[2];
            loc[k].off = off;
        }
        off += words * W;
    }
    return 0; /* full */
}

/* The newest sequence number of sector i's records (loc: its kinds). */
static uint32_t top_seq(const kind_loc_t loc[MC_CFG_KINDS])
{
    uint32_t top = 0u;
    for (uint32_t k = 0u; k < MC_CFG_KINDS; ++k) {
        if (loc[k].have && ((top == 0u) || mc_cfg_store_seq_newer(loc[k].seq, top))) {
            top = loc[k].seq;
        }
    }
    return top;
}

/* The home sector (mc_cfg_store.h, "Record kinds"): the one holding the
 * newest record of every kind; both: the newer; neither (only after a
 * corruption): the sector of the first kind that has a record. sec_of: the
 * sector of each kind's newest, -1 none. */
static int32_t home_of(const kind_loc_t loc[2][MC_CFG_KINDS], const int32_t sec_of[MC_CFG_KINDS])
{
    bool complete[2] = {true, true};
    int32_t first = -1;
    for (uint32_t k = 0u; k < MC_CFG_KINDS; ++k) {
        if (sec_of[k] < 0) {
            continue;
        }
        first = (first < 0) ? sec_of[k] : first;
        for (uint32_t i = 0u; i < 2u; ++i) {
            if (!loc[i][k].have || (loc[i][k].seq != loc[sec_of[k]][k].seq)) {
                complete[i] = false;
            }
        }
    }
    if (first < 0) {
        return -1;
    }
    if (complete[0] && complete[1]) {
        return mc_cfg_store_seq_newer(top_seq(loc[1]), top_seq(loc[0])) ? 1 : 0;
    }
    if (complete[0] || complete[1]) {
        return complete[0] ? 0 : 1;
    }
    return first;
}

static int scan(mc_cfg_store_t *s, bool *p_any)
{
    kind_loc_t loc[2][MC_CFG_KINDS];
    int32_t sec_of[MC_CFG_KINDS];
    (void)memset(loc, 0, sizeof loc);
    s->seq_top = 0u;
    s->scanned = false;
    *p_any = false;
    for (uint32_t k = 0u; k < MC_CFG_KINDS; ++k) {
        s->kind_sec[k] = -1;
        s->kind_off[k] = 0u;
        s->kind_seq[k] = 0u;
        sec_of[k] = -1;
    }
    sync_own(s);
    for (uint32_t i = 0u; i < 2u; ++i) {
        if (scan_sector(s, i, p_any, loc[i]) != 0) {
            return -EIO;
        }
    }
    for (uint32_t k = 0u; k < MC_CFG_KINDS; ++k) {
        for (uint32_t i = 0u; i < 2u; ++i) {
            if (loc[i][k].have &&
                ((sec_of[k] < 0) || mc_cfg_store_seq_newer(loc[i][k].seq, loc[sec_of[k]][k].seq))) {
                sec_of[k] = (int32_t)i;
            }
        }
    }
    s->home = home_of((const kind_loc_t(*)[MC_CFG_KINDS])loc, sec_of);
    for (uint32_t k = 0u; k < MC_CFG_KINDS; ++k) {
        int32_t i = sec_of[k];
        if (i < 0) {
            continue;
        }
        /* a copy with the same number in the home sector: read that one */
        if (loc[s->home][k].have && (loc[s->home][k].seq == loc[i][k].seq)) {
            i = s->home;
        }
        s->kind_sec[k] = i;
        s->kind_off[k] = loc[i][k].off;
        s->kind_seq[k] = loc[i][k].seq;
        if ((s->seq_top == 0u) || mc_cfg_store_seq_newer(loc[i][k].seq, s->seq_top)) {
            s->seq_top = loc[i][k].seq;
        }
    }
    sync_own(s);
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
    s->rec[k++] = k_magic[own_cfg(s)];
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

/* Before a write: the flash as it is now (another axis's store on the same
 * sectors may have written since this one last looked). */
static int rescan(mc_cfg_store_t *s)
{
    bool any = false;
    return scan(s, &any);
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
    if ((s == NULL) || (p == NULL) || (rescan(s) != 0) || (s->active < 0)) {
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

/* Program bytes from RAM at off of sector i (a multiple of W). */
static int program_mem(const mc_cfg_store_t *s, uint32_t i, uint32_t off, const void *src,
                       uint32_t bytes)
{
    const uint8_t *p = src;
    uint32_t buf[16];
    for (uint32_t k = 0u; k < bytes;) {
        const uint32_t n = ((bytes - k) > (uint32_t)sizeof buf) ? (uint32_t)sizeof buf : bytes - k;
        (void)memcpy(buf, p + k, n);
        if (mc_hal_flash_program(s->cfg.flash, s->cfg.sector[i], off + k, buf, n / W) != 0) {
            return -EIO;
        }
        k += n;
    }
    return 0;
}

/* Copy a record of words words from (fi, fo) to (ti, to), word for word. */
static int copy_record(const mc_cfg_store_t *s, uint32_t fi, uint32_t fo, uint32_t ti, uint32_t to,
                       uint32_t words)
{
    uint32_t buf[16];
    for (uint32_t k = 0u; k < words;) {
        const uint32_t n = ((words - k) > 16u) ? 16u : words - k;
        if ((mc_hal_flash_read(s->cfg.flash, s->cfg.sector[fi], fo + k * W, buf, n * W) != 0) ||
            (mc_hal_flash_program(s->cfg.flash, s->cfg.sector[ti], to + k * W, buf, n) != 0)) {
            return -EIO;
        }
        k += n;
    }
    return 0;
}

/* The other kinds' newest records a save of kind keeps: cw[k] their
 * lengths in words (0: none, and 0 for kind itself). 0 or -EIO (one was
 * valid during the scan, not now). */
static int others(const mc_cfg_store_t *s, uint32_t kind, uint32_t cw[MC_CFG_KINDS])
{
    for (uint32_t k = 0u; k < MC_CFG_KINDS; ++k) {
        uint32_t hdr[MC_CFG_HDR_WORDS];
        cw[k] = 0u;
        if ((k != kind) && (s->kind_sec[k] >= 0) &&
            (check_record(s, (uint32_t)s->kind_sec[k], s->kind_off[k], &cw[k], hdr) != 0)) {
            return -EIO;
        }
    }
    return 0;
}

/* Bytes of the other kinds' records a save into target must copy there
 * (those whose newest is in the other sector). */
static uint32_t copy_bytes(const mc_cfg_store_t *s, const uint32_t cw[MC_CFG_KINDS],
                           uint32_t target)
{
    uint32_t b = 0u;
    for (uint32_t k = 0u; k < MC_CFG_KINDS; ++k) {
        if ((cw[k] != 0u) && ((uint32_t)s->kind_sec[k] != target)) {
            b += cw[k] * W;
        }
    }
    return b;
}

/* Where a save of bytes writes (mc_cfg_store.h, "Record kinds"): *p_off in
 * *p_target, erased first when it is the other sector (then lost[k]: kind
 * k's newest was only there). Returns 0, -ENOSPC or -EIO (nothing
 * written). */
static int save_place(mc_cfg_store_t *s, const uint32_t cw[MC_CFG_KINDS], uint32_t bytes,
                      uint32_t *p_target, uint32_t *p_off, bool lost[MC_CFG_KINDS])
{
    uint32_t target = (s->home >= 0) ? (uint32_t)s->home : 0u;
    for (uint32_t k = 0u; k < MC_CFG_KINDS; ++k) {
        lost[k] = false;
    }
    /* append: with copies of the kinds the home sector lacks (only after a
     * corruption) */
    *p_off = s->append_off[target];
    if (region_erased(s, target, *p_off, bytes + copy_bytes(s, cw, target))) {
        *p_target = target;
        return 0;
    }
    /* switch: the other sector holds only older records; every other
     * kind's newest is copied from the home sector (a kind whose only copy
     * was in the sector erased was lost before, by a corruption of the
     * home sector) */
    target ^= 1u;
    for (uint32_t k = 0u; k < MC_CFG_KINDS; ++k) {
        lost[k] = (cw[k] != 0u) && ((uint32_t)s->kind_sec[k] == target);
    }
    if (bytes + copy_bytes(s, cw, target) > s->sector_bytes[target]) {
        return -ENOSPC;
    }
    *p_off = 0u;
    *p_target = target;
    s->append_off[target] = MC_CFG_OFF_NONE;
    return (mc_hal_flash_erase(s->cfg.flash, s->cfg.sector[target]) != 0) ? -EIO : 0;
}

/* Copy the other kinds' records that target lacks to *p_off there (each
 * checked), their new places into sec/off. 0 or -EIO. */
static int copy_others(const mc_cfg_store_t *s, const uint32_t cw[MC_CFG_KINDS], uint32_t target,
                       uint32_t *p_off, int32_t sec[MC_CFG_KINDS], uint32_t off[MC_CFG_KINDS])
{
    for (uint32_t k = 0u; k < MC_CFG_KINDS; ++k) {
        uint32_t words = 0u;
        uint32_t rb[MC_CFG_HDR_WORDS];
        sec[k] = s->kind_sec[k];
        off[k] = s->kind_off[k];
        if ((cw[k] == 0u) || ((uint32_t)s->kind_sec[k] == target)) {
            continue;
        }
        if ((copy_record(s, (uint32_t)s->kind_sec[k], s->kind_off[k], target, *p_off, cw[k]) !=
             0) ||
            (check_record(s, target, *p_off, &words, rb) != 0) || (words != cw[k])) {
            return -EIO;
        }
        sec[k] = (int32_t)target;
        off[k] = *p_off;
        *p_off += cw[k] * W;
    }
    return 0;
}

/* Write a record of kind: header hdr (its sequence number in hdr[2]),
 * payload, CRC; read back. On success every kind's place is updated. */
static int save_rec(mc_cfg_store_t *s, uint32_t kind, const uint32_t hdr[MC_CFG_HDR_WORDS],
                    const void *payload, uint32_t payload_bytes)
{
    const uint32_t bytes = ((MC_CFG_HDR_WORDS + 1u) * W) + payload_bytes;
    const uint32_t crc = mc_crc32_final(mc_crc32_update(
        mc_crc32_update(MC_CRC32_INIT, hdr, (size_t)MC_CFG_HDR_WORDS * W), payload, payload_bytes));
    uint32_t cw[MC_CFG_KINDS];
    bool lost[MC_CFG_KINDS];
    int32_t sec[MC_CFG_KINDS];
    uint32_t off_k[MC_CFG_KINDS];
    uint32_t target = 0u;
    uint32_t off = 0u;
    uint32_t words = 0u;
    uint32_t rb[MC_CFG_HDR_WORDS];
    int rc = others(s, kind, cw);
    if (rc == 0) {
        rc = save_place(s, cw, bytes, &target, &off, lost);
    }
    if (rc != 0) {
        return rc;
    }
    if ((copy_others(s, cw, target, &off, sec, off_k) != 0) ||
        (program_mem(s, target, off, hdr, MC_CFG_HDR_WORDS * W) != 0) ||
        (program_mem(s, target, off + (MC_CFG_HDR_WORDS * W), payload, payload_bytes) != 0) ||
        (program_mem(s, target, off + bytes - W, &crc, W) != 0) ||
        (check_record(s, target, off, &words, rb) != 0) || (words * W != bytes) ||
        (rb[2] != hdr[2])) {
        s->append_off[target] = MC_CFG_OFF_NONE; /* not again before an erase */
        s->scanned = false;                      /* the places: from the flash again */
        return -EIO;
    }
    for (uint32_t k = 0u; k < MC_CFG_KINDS; ++k) {
        s->kind_sec[k] = lost[k] ? -1 : sec[k];
        s->kind_off[k] = off_k[k];
    }
    s->kind_sec[kind] = (int32_t)target;
    s->kind_off[kind] = off;
    s->kind_seq[kind] = hdr[2];
    s->seq_top = hdr[2];
    s->home = (int32_t)target;
    s->append_off[target] = off + bytes;
    s->saves++;
    sync_own(s);
    return 0;
}

int mc_cfg_store_save(mc_cfg_store_t *s, const mc_params_t *p)
{
    if ((s == NULL) || (p == NULL) || (mc_params_validate(p) != MC_PARAMS_OK)) {
        return -EINVAL;
    }
    if (rescan(s) != 0) {
        return -EIO;
    }
    build_record(s, p, mc_cfg_store_seq_next(s->seq_top));
    return save_rec(s, own_cfg(s), s->rec, &s->rec[MC_CFG_HDR_WORDS],
                    (MC_CFG_REC_WORDS - MC_CFG_HDR_WORDS - 1u) * W);
}

int mc_cfg_store_save_map(mc_cfg_store_t *s, const void *map, uint32_t bytes)
{
    uint32_t hdr[MC_CFG_HDR_WORDS];
    if ((s == NULL) || (map == NULL) || (bytes == 0u) || ((bytes % (2u * W)) != 0u) ||
        (bytes / (2u * W) > MC_CFG_ENTRIES_MAX)) {
        return -EINVAL;
    }
    if (rescan(s) != 0) {
        return -EIO;
    }
    hdr[0] = k_magic[own_map(s)];
    hdr[1] = MC_CFG_FORMAT;
    hdr[2] = mc_cfg_store_seq_next(s->seq_top);
    hdr[3] = (bytes / (2u * W)) | 0xFFFF0000u;
    return save_rec(s, own_map(s), hdr, map, bytes);
}

int mc_cfg_store_load_map(mc_cfg_store_t *s, void *map, uint32_t bytes)
{
    uint32_t hdr[MC_CFG_HDR_WORDS];
    uint32_t words = 0u;
    uint8_t *p = map;
    if ((s == NULL) || (map == NULL)) {
        return -EINVAL;
    }
    if (scan_once(s) != 0) {
        return -EIO;
    }
    if (s->map_sec < 0) {
        return -ENOENT;
    }
    if (check_record(s, (uint32_t)s->map_sec, s->map_off, &words, hdr) != 0) {
        return -EIO;
    }
    if ((hdr[1] != MC_CFG_FORMAT) || ((hdr[3] & 0xFFFFu) * 2u * W != bytes)) {
        return -EBADMSG;
    }
    for (uint32_t k = 0u; k < bytes; k += W) {
        uint32_t w;
        if (read_word(s, (uint32_t)s->map_sec, s->map_off + (MC_CFG_HDR_WORDS * W) + k, &w) != 0) {
            return -EIO;
        }
        (void)memcpy(p + k, &w, W);
    }
    return 0;
}
