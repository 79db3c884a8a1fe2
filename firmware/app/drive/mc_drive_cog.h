/**
 * @file mc_drive_cog.h
 * @brief The anticogging map: the q-axis current that cancels the motor's
 *        cogging torque, per mechanical angle, and its feed-forward lookup.
 *
 * Map (mc_cog_map_t, 2088 bytes, 32-bit words with the entries packed two
 * per word, little-endian, CRC last):
 *   magic    0x474F434D ("MCOG")
 *   format   MC_COG_FORMAT (bits 0..15) | MC_COG_N (bits 16..31)
 *   the encoder identity it was measured with (mc_cog_ident_t):
 *            encoder_type, encoder_cpr, encoder_reversed, pole_pairs,
 *            encoder_offset_rad (IEEE 754 single)
 *   scale_a  amperes per entry unit (IEEE 754 single, >= 0): entry k is
 *            q[k] * scale_a, the current at mechanical angle k 2 pi / N
 *   q[N]     N = 1024 signed 16-bit entries (q15 of the full scale
 *            32767 scale_a, the largest |entry| of the map)
 *   order    the order the entries were filtered to (mc_cog_order:
 *            lcm(slots, 2 p) per turn, below N / 2), 0: every order kept
 *            (a map of format 1 before this word had a meaning holds 0
 *            there: read as every order, as it was built)
 *   crc      CRC-32 (zlib, mc_crc32) of every byte before it
 *
 * N = 1024 over one mechanical turn: a cogging harmonic of order k (the
 * least common multiple of slots and poles and its multiples, e.g. 12
 * slots / 14 poles: 84) has N / k >= 12 bins per period up to k = 85, where
 * linear interpolation's error is at most (2 pi k / N)^2 / 8 of its
 * amplitude (the second derivative's bound times h^2 / 8): 3.4 % at k = 84,
 * 0.07 % at k = 12. q15 adds half an LSB of the full scale (1.5e-5).
 *
 * Build (mc_cog_build): from N q-axis currents [A], one per mechanical-angle
 * bin k (angle k 2 pi / N, in the rotor's positive direction: what the
 * drive's theta_m_rad reads), as a calibration measures them. The mean is
 * removed (a constant current is friction or load, not cogging); with an
 * order (mc_cog_order: lcm(slots, 2 p)), only its multiples below N / 2
 * are kept (at most MC_COG_KEEP_MAX: a projection on their Fourier series,
 * exact at the bins; order 0 keeps every order): a slotted motor's cogging
 * has no other, and what the calibration leaves there is its speed loop's
 * noise, which the feed-forward would inject. Refused:
 * a non-finite entry (MC_COG_ST_NONFINITE), an entry whose |value - mean|
 * exceeds i_bound_a (MC_COG_ST_AMPLITUDE: the caller passes the share of the
 * current limit a feed-forward may take), an identity or bound that is not
 * valid or an order not below N / 2 (MC_COG_ST_ARG). On refusal *map is
 * not changed.
 *
 * Validate (mc_cog_check): magic, format or N of another layout
 * (MC_COG_ST_LAYOUT), CRC (MC_COG_ST_CRC), scale not finite or negative
 * (MC_COG_ST_LAYOUT), another encoder (MC_COG_ST_ENCODER): the type, counts
 * per turn, direction or pole pairs differ, or the encoder offset moved by
 * more than MC_COG_OFFSET_TOL_M_RAD mechanical (half a bin: a recommission
 * measures the same mounting within it; a remounted encoder moves its
 * zero, and the map would cancel the cogging at the wrong angle), or the
 * drive's own identity is not one a map fits (no encoder: encoder_cpr 0).
 *
 * Lookup (mc_cog_ff_a): linear interpolation between the two bins around
 * theta_m_rad, bin N-1 to bin 0 across 2 pi; any finite angle (wrapped);
 * a non-finite one gives 0. About 20 instructions, no division.
 *
 * Series (mc_cog_series_init, mc_cog_series_ff_adv_a): a map filtered to
 * the multiples of an order holds nothing else, so its kept orders'
 * Fourier coefficients (projected from the entries once, when the map is
 * attached) give its value at any angle exactly, where the interpolation
 * between bins keeps cos(pi k / N) of a term of order k at mid-bin (the
 * mean of the two bins): 0.97 at k = 84, 0.69 at k = 264 (a 24-slot,
 * 22-pole gimbal motor: 3.9 bins per period). One
 * sine and cosine of order theta (at the current's lead) and the kept
 * multiples by the angle-addition recursion, which also gives the
 * derivatives the rate of change's lead takes (mc_cog_series_ff_adv_a); its
 * cost on the M4F: targets/stm32f405/README.md, block mcu-isr-parts.
 */
#ifndef MC_DRIVE_COG_H
#define MC_DRIVE_COG_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_COG_MAGIC  0x474F434Du /**< "MCOG" in memory order */
#define MC_COG_FORMAT 1u
#define MC_COG_N      1024u /**< entries per mechanical turn (a power of two) */
/** Most orders a filtered map keeps (mc_cog_keep_count): the cost of a
 *  build is 3 N sines per kept order. */
#define MC_COG_KEEP_MAX 8u
/** Largest encoder-offset move [rad mechanical] a map survives: half a bin. */
#define MC_COG_OFFSET_TOL_M_RAD (3.14159265f / (float)MC_COG_N)

/** Map status (the readonly parameter cog_status). */
typedef enum {
    MC_COG_ST_OK = 0,        /**< a valid map for this encoder */
    MC_COG_ST_EMPTY = 1,     /**< no map loaded (none stored) */
    MC_COG_ST_LAYOUT = 2,    /**< magic, format, N or scale of another layout */
    MC_COG_ST_CRC = 3,       /**< the CRC does not match */
    MC_COG_ST_ENCODER = 4,   /**< measured with another encoder / offset / pole pairs */
    MC_COG_ST_NONFINITE = 5, /**< build: an entry is NaN or infinite */
    MC_COG_ST_AMPLITUDE = 6, /**< build: |entry - mean| beyond the bound */
    MC_COG_ST_ARG = 7,       /**< NULL, a bad bound or identity, a wrong count */
    MC_COG_ST_FLASH = 8,     /**< the stored map could not be read or written */
} mc_cog_status_t;

/** The encoder (and motor) a map was measured with. */
typedef struct {
    uint32_t enc_type;     /**< encoder_type parameter */
    uint32_t enc_cpr;      /**< encoder_cpr, > 0 */
    uint32_t enc_reversed; /**< encoder_reversed, 0/1 */
    uint32_t pole_pairs;   /**< >= 1 */
    float enc_offset_rad;  /**< encoder_offset_rad (electrical) */
} mc_cog_ident_t;

typedef struct {
    uint32_t magic;
    uint32_t format; /**< MC_COG_FORMAT | MC_COG_N << 16 */
    mc_cog_ident_t ident;
    float scale_a;       /**< A per unit of q */
    uint32_t order;      /**< the kept order (mc_cog_order), 0: every order; also
                              makes the map a whole number of the store's 8-byte
                              pairs */
    int16_t q[MC_COG_N]; /**< the entries, bin k at k 2 pi / N mechanical */
    uint32_t crc;        /**< CRC-32 of the bytes above */
} mc_cog_map_t;

/** A map's kept orders as a Fourier series (mc_cog_series_init): the
 *  current at mechanical angle th is sum_m a[m] cos(j th) + b[m] sin(j th),
 *  j = (m + 1) order, m < count. count 0: the map keeps every order (or
 *  none was given): the drive interpolates its bins instead. */
typedef struct {
    uint32_t order;
    uint32_t count;
    float a[MC_COG_KEEP_MAX];
    float b[MC_COG_KEEP_MAX];
} mc_cog_series_t;

/** Words of a map (the flash record's payload). */
#define MC_COG_MAP_WORDS ((uint32_t)(sizeof(mc_cog_map_t) / 4u))

/** Build *map from n = MC_COG_N currents [A] (above). */
mc_cog_status_t mc_cog_build(mc_cog_map_t *map, const float *i_q_a, uint32_t n,
                             const mc_cog_ident_t *ident, float i_bound_a, uint32_t order);

/** The order whose multiples a slotted motor's cogging has:
 *  lcm(slots, 2 pole_pairs) per turn (Zhu and Howe 2000), or 0 (keep every
 *  order) when slots or pole_pairs is 0 or above 1000 or the order is not
 *  below N / 2 (the map could not hold one period of it). */
uint32_t mc_cog_order(uint32_t slots, uint32_t pole_pairs);

/** How many multiples of order (1 .. count) a map built with it keeps:
 *  those below N / 2, at most MC_COG_KEEP_MAX; 0 for order 0. */
uint32_t mc_cog_keep_count(uint32_t order);

/** Validate a map against the drive's encoder (above). NULL map: EMPTY. */
mc_cog_status_t mc_cog_check(const mc_cog_map_t *map, const mc_cog_ident_t *ident);

/** The CRC a map must carry (over every byte before crc). */
uint32_t mc_cog_crc(const mc_cog_map_t *map);

/** The feed-forward current at the mechanical angle [A] (above). The map
 *  must have passed mc_cog_check. */
float mc_cog_ff_a(const mc_cog_map_t *map, float theta_m_rad);

/** The current loop the feed-forward goes through (mc_cog_ff_adv_a): a
 *  reference r(k) taken at sample k acts, after one period of computation,
 *  over the next period, from the current i(k+1) it finds then:
 *  i(k+2) = i(k+1) + (T / tau) (r(k) - i(k+1)), tau = L / kp (1 / the
 *  loop's bandwidth: the PI's zero cancels the winding's pole). For the
 *  current to follow the map I(theta) the reference is
 *    r(k) = I(theta(k+1)) + tau (I(theta(k+2)) - I(theta(k+1))) / T
 *         ~ I(theta + w lead_i) + tau w I'(theta + w lead_d),
 *  lead_i = T (where the voltage starts to act), lead_d = 1.5 T (the middle
 *  of the period it acts over). Measured on the SK3 at 10 % of its rated
 *  speed, the cogging at 2.1 times the loop's bandwidth: the current within
 *  3 % of the map's in amplitude and 0.01 rad in phase; a first-order lag
 *  behind one lead of 1.5 T for both terms drove 8 % too much, 0.075 rad
 *  late (commission/README.md). */
typedef struct {
    float lead_i_s; /**< the current's lead [s], >= 0 */
    float lead_d_s; /**< its rate of change's lead [s], >= 0 */
    float tau_s;    /**< the loop's time constant [s], >= 0 */
} mc_cog_loop_t;

/** The feed-forward through that loop from the map's bins: *p_i_a the
 *  current to flow, the map at the angle lead_i ahead at rate_rad_s
 *  (interpolated), the return value plus tau times the rate of change at
 *  lead_d: rate times the slope between the lookups half a bin either side.
 *  A rate of 0 gives mc_cog_ff_a's value. */
float mc_cog_ff_adv_a(const mc_cog_map_t *map, float theta_m_rad, float rate_rad_s,
                      const mc_cog_loop_t *lp, float *p_i_a);

/** The series of a map that passed mc_cog_check: its order's kept
 *  multiples projected from the entries (2 / N sum q[k] scale cos, sin of
 *  the bin's angle: exact for a map the builder filtered, to the entries'
 *  q15 rounding); count 0 for a map of order 0. N count sines: about 2 ms
 *  on the M4F at count 8, for the slow context that attaches a map. */
void mc_cog_series_init(mc_cog_series_t *s, const mc_cog_map_t *map);

/** The series feed-forward's fade with frequency: a term whose frequency
 *  (its order times the speed) is more than MC_COG_FADE_START times the
 *  current loop's bandwidth (1 / tau) is weighed down linearly, to 0 at
 *  MC_COG_FADE_END. Past a few times the bandwidth the loop's inverse asks
 *  for a reference that many times the map's current (on the SK3 at 80 %
 *  of rated speed, order 84 at 17 times the bandwidth: 28 A peak-to-peak
 *  for a 1.6 A map, and no less ripple), while the rotor's inertia has long
 *  filtered the cogging out of the speed. Up to 4 times it reproduces the
 *  map within a few percent (the SK3 at 10 % of rated speed: 2.1 times). */
#define MC_COG_FADE_START 4.0f
#define MC_COG_FADE_END   8.0f

/** mc_cog_ff_adv_a's feed-forward from the series, each term faded by its
 *  frequency (above), in one pass with one sine and cosine: the current
 *  exact at lead_i, and its derivative in angle at lead_d by a Taylor step
 *  from lead_i with the series' first three derivatives there. A term of
 *  order j and amplitude A errs by at most j A p^3 / 6 in the derivative,
 *  p = j |rate| (lead_d - lead_i) its phase step. With the drive's leads
 *  (lead_d - lead_i = T / 2), a term at x times the loop's bandwidth has
 *  p = x bw T / 2: with the default bw T = 0.08, 0.07 % of its derivative
 *  at x = 4 and 0.23 % at x = 6; with the largest, 0.3 (MC_PARAMS_BW_DT_MAX),
 *  3.6 % and 12 %, where the loop's own difference over a period is already
 *  sin(p) / p of the derivative the reference takes (13 % less at x = 6).
 *  A non-finite angle or rate gives 0. */
float mc_cog_series_ff_adv_a(const mc_cog_series_t *s, float theta_m_rad, float rate_rad_s,
                             const mc_cog_loop_t *lp, float *p_i_a);

/** The bins path's fade (mc_cog_ff_adv_a has no orders to fade one by
 *  one): the map's RMS order, (N / 2 pi) times the RMS of its bin-to-bin
 *  differences over the RMS of its entries (cyclic). It is the factor the
 *  bins path's rate term carries: at speed w that term is tau w times it
 *  times the map's RMS, as a term of that order would be, so the drive
 *  fades the whole lookup (mc_cog_fade_gain) at tau w times this order, as
 *  the series fades each term. A single order j reads N sin(pi j / N) / pi,
 *  under j by 1.1 % at 84 and 10.6 % at 264 (the half-bin slope's); noise
 *  at high orders reads higher and fades the map at a lower speed. 0 for a map of zero entries. N
 *  differences: for the context that attaches a map. */
float mc_cog_map_order_rms(const mc_cog_map_t *map);

/** The fade of a feed-forward term whose frequency is x times the current
 *  loop's bandwidth: 1 up to MC_COG_FADE_START, 0 from MC_COG_FADE_END
 *  (and for a non-finite x), linear between. */
float mc_cog_fade_gain(float x);

/** The order a calibration with the slots unknown (cog_slots 0) keeps:
 *  of the orders lcm(Q, 2 pole_pairs) below N / 2 a three-phase stator can
 *  have (Q a multiple of 3, up to 1000), the one whose line in the n =
 *  MC_COG_N currents i_q_a is the strongest (Goertzel), when its power is
 *  at least MC_COG_FIND_SNR times the currents' mean power per order; 0
 *  (keep every order) when none is, or for bad arguments. Noise spreads
 *  over the 511 orders: of pure noise the strongest of the (at most 85)
 *  candidates reaches 25 times the mean with a probability of 85 e^-25,
 *  1e-9.
 *  About 1024 multiply-adds per candidate (85 at most), for the context that
 *  builds a map. */
uint32_t mc_cog_find_order(const float *i_q_a, uint32_t n, uint32_t pole_pairs);
#define MC_COG_FIND_SNR 25.0f

#ifdef __cplusplus
}
#endif

#endif /* MC_DRIVE_COG_H */
