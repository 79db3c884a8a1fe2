/**
 * @file mc_cfg_store.h
 * @brief The configuration store: the parameters in two flash sectors (A/B)
 *        as versioned, CRC-32-protected records; the newest valid record
 *        wins at boot; a save survives a power cut at any step.
 *
 * Record (32-bit little-endian words, programmed in this order, the CRC
 * last):
 *   0  magic 0x4746434D ("MCFG")
 *   1  format (bits 0..15, MC_CFG_FORMAT) | table layout version (16..31,
 *      MC_PARAMS_LAYOUT_VERSION of the firmware that wrote it)
 *   2  sequence number (1, 2, ...: one more than the newest record seen;
 *      after 0xFFFFFFFF comes 1, 0 is never written)
 *   3  n = number of entries (bits 0..15; bits 16..31 are 0xFFFF)
 *   4 ..          n entries of two words: parameter id, raw value
 *   4 + 2n        CRC-32 of words 0 .. 3 + 2n
 * Records follow each other from the start of a sector; the first erased
 * word (0xFFFFFFFF where a magic would be) is where the next one goes.
 *
 * Save: the new record is appended behind the newest in its sector if it
 * fits (in erased words); otherwise the other sector is erased and the
 * record written at its start. The sector holding the newest record is
 * never erased or overwritten, so a cut at any step leaves either the old
 * newest record (the new one has no valid CRC) or the new one. The record
 * is read back and its CRC checked before the save reports success.
 *
 * Sequence numbers are compared in serial-number arithmetic (RFC 1982):
 * a is newer than b when (int32_t)(a - b) > 0. Every valid record in the
 * two sectors was written since the older sector's last erase, so their
 * numbers span far less than 2^31 and the newest is well defined across
 * the wrap from 0xFFFFFFFF to 1 (protocol 3's store compared them as
 * plain integers: the save after 0xFFFFFFFF wrote 0, was answered OK, and
 * the next boot took the old record).
 *
 * Unchanged: mc_cfg_store_holds() tells whether the newest record already
 * holds exactly the record a save of p would write (format, layout, every
 * id and raw value): the parameter service skips such a SAVE (no erase,
 * no program: flash wear is a budget, mc_param_srv.h).
 *
 * Boot (mc_cfg_store_load): both sectors are scanned; a sector's scan ends
 * at an erased word or at the first word sequence that is not a valid
 * record (a cut record: the rest of that sector is not used again until it
 * is erased). Of all valid records the newest (above) is decoded:
 *   format differs, or a layout version other than this firmware's that no
 *   migration knows        -> MC_CFG_BOOT_LAYOUT, defaults (named fault)
 *   a value out of range, or the whole set refused by mc_params_validate
 *                           -> MC_CFG_BOOT_INVALID, defaults
 *   ids missing (a parameter added since) or unknown (one removed): those
 *   take their default / are dropped, then validated as a whole
 *                           -> MC_CFG_BOOT_MIGRATED
 *   otherwise              -> MC_CFG_BOOT_STORED
 * Record kinds: the configuration (magic MCFG) and the anticogging map
 * (magic MC_CFG_MAP_MAGIC "MCMP", the same envelope: words 0..3 as above
 * with format | 0 << 16, the map's bytes as its n pairs of words, the
 * CRC), written only by a calibration's save (mc_cfg_store_save_map). One
 * sequence counter numbers both. The sector saves append to (home) always
 * holds the newest record of each kind: a save that must switch sectors
 * erases the other one, copies the newest record of the other kind into it
 * word for word (its sequence number kept), then writes the new record. A
 * cut leaves the home sector untouched, so each kind keeps its old newest
 * record or gets the new one. At boot the home sector is the one holding
 * the newest record of every kind (after a cut switch, the old one; both:
 * the one with the newer record). A map record of another size or format
 * is refused by mc_cfg_store_load_map (-EBADMSG), never decoded.
 * Axes (a two-axis board, issue 34): the configuration and the map of
 * axis 1 are two more kinds (magics MC_CFG_MAGIC_AX1 "MCF1" and
 * MC_CFG_MAP_MAGIC_AX1 "MCM1"; axis 0's keep MCFG and MCMP, so a one-axis
 * board's store is its axis 0's). mc_cfg_store_cfg_t.axis says which
 * axis's kinds a store loads and saves; the two axes' stores share the two
 * sectors and one sequence counter, and the home sector holds the newest
 * record of all four kinds (a save that switches sectors copies the newest
 * of each other kind, the other axis's included). A store rescans both
 * sectors before every save and before mc_cfg_store_holds, so the other
 * axis's saves since are seen (the two saves must not run at the same
 * time: on the board both run from the one slow loop). An image of an
 * older layout does not know the axis-1 kinds: it skips them by their
 * length, and a sector switch it makes does not copy them.
 * No valid record: MC_CFG_BOOT_EMPTY if both sectors start erased, else
 * MC_CFG_BOOT_CORRUPT; defaults either way. The status goes into the
 * heartbeat (HEARTBEAT.cfg_status) and the readonly parameter
 * cfg_store_status.
 */
#ifndef MC_CFG_STORE_H
#define MC_CFG_STORE_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/flash.h"
#include "mc_params.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_CFG_MAGIC         0x4746434Du        /**< "MCFG" in memory order */
#define MC_CFG_MAP_MAGIC     0x504D434Du        /**< "MCMP": an anticogging map record */
#define MC_CFG_MAGIC_AX1     0x3146434Du        /**< "MCF1": axis 1's configuration */
#define MC_CFG_MAP_MAGIC_AX1 0x314D434Du        /**< "MCM1": axis 1's anticogging map */
#define MC_CFG_AXES          2u                 /**< axes whose records a store tells apart */
#define MC_CFG_KINDS         (2u * MC_CFG_AXES) /**< configuration and map per axis */
#define MC_CFG_FORMAT        1u
#define MC_CFG_HDR_WORDS     4u
#define MC_CFG_ENTRIES_MAX   1024u /**< a header announcing more is not a record */
/** Words of a record this firmware writes. */
#define MC_CFG_REC_WORDS (MC_CFG_HDR_WORDS + 2u * MC_PARAM_STORED_COUNT + 1u)
#define MC_CFG_OFF_NONE  0xFFFFFFFFu

/** How the configuration was obtained at boot. */
typedef enum {
    MC_CFG_BOOT_STORED = 0,   /**< newest record, every parameter */
    MC_CFG_BOOT_MIGRATED = 1, /**< newest record, ids added/removed since */
    MC_CFG_BOOT_EMPTY = 2,    /**< nothing stored: defaults */
    MC_CFG_BOOT_CORRUPT = 3,  /**< no valid record, but not erased: defaults */
    MC_CFG_BOOT_LAYOUT = 4,   /**< newest record of another format/layout: defaults */
    MC_CFG_BOOT_INVALID = 5,  /**< newest record fails validation: defaults */
    MC_CFG_BOOT_FLASH = 6,    /**< the flash could not be read: defaults */
} mc_cfg_boot_t;

typedef struct {
    const mc_hal_flash_t *flash;
    uint32_t sector[2]; /**< A and B: two distinct sectors of the flash */
    uint32_t axis;      /**< whose records this store loads and saves: 0 (M0, and a
                             one-axis board) or 1 (M1); see "Axes" above */
} mc_cfg_store_cfg_t;

typedef struct {
    mc_cfg_store_cfg_t cfg;
    uint32_t sector_bytes[2];
    int32_t kind_sec[MC_CFG_KINDS];  /**< each kind's newest record: its sector, -1 none */
    uint32_t kind_off[MC_CFG_KINDS]; /**< its offset */
    uint32_t kind_seq[MC_CFG_KINDS]; /**< its sequence number */
    /* This axis's view of the above (kept in step with it): */
    uint32_t seq;           /**< sequence number of the newest valid configuration
                                 record (0: none) */
    int32_t active;         /**< 0/1: the sector of the newest valid configuration
                                 record; -1: none */
    uint32_t newest_off;    /**< its offset */
    uint32_t seq_top;       /**< the newest sequence number of any kind (0: none) */
    int32_t home;           /**< 0/1: the sector saves append to, holding the newest
                                 record of each kind; -1: no record */
    int32_t map_sec;        /**< 0/1: the sector of the newest map record; -1: none */
    uint32_t map_off;       /**< its offset */
    uint32_t append_off[2]; /**< next free offset per sector, MC_CFG_OFF_NONE if unusable */
    bool scanned;
    mc_cfg_boot_t boot;             /**< result of the last load */
    uint32_t boot_dropped;          /**< entries of the loaded record with unknown ids */
    uint32_t boot_missing;          /**< parameters the loaded record lacked (defaulted) */
    uint32_t saves;                 /**< successful saves since init */
    uint32_t rec[MC_CFG_REC_WORDS]; /**< record being written */
} mc_cfg_store_t;

/** Bind the store to its two sectors (each must hold a record). Returns 0,
 *  -EINVAL (NULL, same sector twice, a sector too small or unknown). */
int mc_cfg_store_init(mc_cfg_store_t *s, const mc_cfg_store_cfg_t *cfg);

/** Scan both sectors and decode the newest valid record into *p_out;
 *  *p_out always receives a validated configuration (the defaults when
 *  the status is not STORED or MIGRATED). */
mc_cfg_boot_t mc_cfg_store_load(mc_cfg_store_t *s, mc_params_t *p_out);

/**
 * The raw value of parameter id in the newest valid record, whatever the
 * record's table layout version (ids keep their meaning across layouts):
 * for readers that do not hold the parameter table, the bootloader (its
 * node id and bit rate). Nothing is validated beyond the record's CRC and
 * format: the caller range-checks the value.
 * @return 0 and *p_raw; -ENOENT (no valid record, another record format, or
 *         no such id in it); -EIO (the flash could not be read); -EINVAL.
 */
int mc_cfg_store_find_raw(mc_cfg_store_t *s, uint32_t id, uint32_t *p_raw);

/**
 * Write p as a new record (p must pass mc_params_validate: the store never
 * holds a configuration the drive would refuse). BLOCKING (may erase a
 * sector): only while the bridge is off.
 * @return 0; -EINVAL (NULL, p invalid; nothing written); -EIO (flash error
 *         or read-back mismatch: the previous record stays the newest).
 */
int mc_cfg_store_save(mc_cfg_store_t *s, const mc_params_t *p);

/**
 * Write an anticogging map (bytes, a multiple of 8, e.g. mc_cog_map_t) as a
 * map record (see "Record kinds" above). BLOCKING, as a save.
 * @return 0; -EINVAL (NULL, bytes 0, not a multiple of 8 or more than a
 *         record holds); -ENOSPC (a sector cannot hold the map and the
 *         configuration record together); -EIO (flash error: the previous
 *         map stays the newest).
 */
int mc_cfg_store_save_map(mc_cfg_store_t *s, const void *map, uint32_t bytes);

/**
 * Read the newest map record into map (bytes long; scans first if needed).
 * @return 0; -ENOENT (no map record); -EBADMSG (a map record of another
 *         size or format: another layout, map not changed); -EIO (flash);
 *         -EINVAL.
 */
int mc_cfg_store_load_map(mc_cfg_store_t *s, void *map, uint32_t bytes);

/** The sequence number after seq (1 after 0xFFFFFFFF: 0 means none). */
uint32_t mc_cfg_store_seq_next(uint32_t seq);

/** a newer than b in serial-number arithmetic ((int32_t)(a - b) > 0). */
bool mc_cfg_store_seq_newer(uint32_t a, uint32_t b);

/**
 * The newest valid record is exactly the record mc_cfg_store_save(s, p)
 * would write, sequence number and CRC aside (scans first if needed).
 * false also for NULL arguments, no record or a flash read error.
 */
bool mc_cfg_store_holds(mc_cfg_store_t *s, const mc_params_t *p);

#ifdef __cplusplus
}
#endif

#endif /* MC_CFG_STORE_H */
