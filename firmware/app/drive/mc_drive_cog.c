/**
 * @file mc_drive_cog.c
 * @brief The anticogging map: see mc_drive_cog.h.
 */
#include "mc_drive_cog.h"

#include <stddef.h>

#include "math/mc_math.h"
#include "config/mc_crc32.h"

#define COG_TWO_PI    6.28318531f
#define COG_PI        3.14159265f
#define COG_BIN_PER_R ((float)MC_COG_N / COG_TWO_PI)

_Static_assert((MC_COG_N & (MC_COG_N - 1u)) == 0u, "MC_COG_N must be a power of two");
_Static_assert(offsetof(mc_cog_map_t, crc) == (sizeof(mc_cog_map_t) - 4u),
               "the map has no padding: the CRC is its last word");
_Static_assert((sizeof(mc_cog_map_t) % 8u) == 0u, "a whole number of the store's 8-byte pairs");

uint32_t mc_cog_crc(const mc_cog_map_t *map)
{
    return mc_crc32(map, offsetof(mc_cog_map_t, crc));
}

static bool ident_valid(const mc_cog_ident_t *id)
{
    return (id != NULL) && (id->enc_cpr > 0u) && (id->enc_reversed <= 1u) &&
           (id->pole_pairs >= 1u) && mc_isfinite_f32(id->enc_offset_rad) &&
           (mc_abs_f32(id->enc_offset_rad) <= 4.0f * COG_PI);
}

/* Round to the nearest integer, halves away from zero (|x| <= 32767.5). */
static int16_t round_q15(float x)
{
    const int32_t r = (int32_t)((x >= 0.0f) ? (x + 0.5f) : (x - 0.5f));
    return (int16_t)((r > 32767) ? 32767 : ((r < -32767) ? -32767 : r));
}

uint32_t mc_cog_order(uint32_t slots, uint32_t pole_pairs)
{
    uint32_t a = slots;
    uint32_t b = 2u * pole_pairs;
    uint32_t l;
    if ((slots == 0u) || (pole_pairs == 0u) || (slots > 1000u) || (pole_pairs > 1000u)) {
        return 0u;
    }
    while (b != 0u) { /* gcd */
        const uint32_t r = a % b;
        a = b;
        b = r;
    }
    l = (slots / a) * 2u * pole_pairs; /* <= 2e6: no overflow */
    return (l < (MC_COG_N / 2u)) ? l : 0u;
}

/* The orders the map keeps (mc_cog_keep_count): multiples m order, m =
 * 1 .. count, below N / 2. */
uint32_t mc_cog_keep_count(uint32_t order)
{
    uint32_t c = 0u;
    if (order > 0u) {
        c = (MC_COG_N / 2u - 1u) / order;
        c = (c > MC_COG_KEEP_MAX) ? MC_COG_KEEP_MAX : c;
    }
    return c;
}

/* Bin k's current [A]: x[k], or (x NULL) the map's entry times its scale. */
static float bin_at(const float *x, const mc_cog_map_t *map, uint32_t k)
{
    return (x != NULL) ? x[k] : (map->scale_a * (float)map->q[k]);
}

/* Fourier coefficients of the kept orders m order (2 / N sum x_k cos / sin
 * of the bin's angle: exact on the uniform grid below N / 2; the mean drops
 * out; each angle reduced to an index mod N before its sine); the bins are
 * x's or (x NULL) the map's. */
static void kept_orders(const float *x, const mc_cog_map_t *map, uint32_t order, uint32_t count,
                        float *a, float *b)
{
    for (uint32_t m = 0u; m < count; ++m) {
        const uint32_t j = (m + 1u) * order;
        float sa = 0.0f;
        float sb = 0.0f;
        for (uint32_t k = 0u; k < MC_COG_N; ++k) {
            float sn;
            float cs;
            mc_sincos_f32((float)((j * k) & (MC_COG_N - 1u)) / COG_BIN_PER_R, &sn, &cs);
            const float v = bin_at(x, map, k);
            sa += v * cs;
            sb += v * sn;
        }
        a[m] = sa * (2.0f / (float)MC_COG_N);
        b[m] = sb * (2.0f / (float)MC_COG_N);
    }
}

/* Bin k of the map before scaling [A]: the kept orders' sum, or (order 0)
 * the current less the mean. */
static float kept_value(const float *x, uint32_t k, float mean, uint32_t order, uint32_t count,
                        const float *a, const float *b)
{
    float v = 0.0f;
    if (order == 0u) {
        return x[k] - mean;
    }
    for (uint32_t m = 0u; m < count; ++m) {
        const uint32_t j = (m + 1u) * order;
        float sn;
        float cs;
        mc_sincos_f32((float)((j * k) & (MC_COG_N - 1u)) / COG_BIN_PER_R, &sn, &cs);
        v += (a[m] * cs) + (b[m] * sn);
    }
    return v;
}

mc_cog_status_t mc_cog_build(mc_cog_map_t *map, const float *i_q_a, uint32_t n,
                             const mc_cog_ident_t *ident, float i_bound_a, uint32_t order)
{
    float sum = 0.0f;
    float mean;
    float fs = 0.0f;
    float inv;
    const uint32_t count = mc_cog_keep_count(order);
    float a[MC_COG_KEEP_MAX];
    float b[MC_COG_KEEP_MAX];
    if ((map == NULL) || (i_q_a == NULL) || (n != MC_COG_N) || !ident_valid(ident) ||
        !mc_isfinite_f32(i_bound_a) || !(i_bound_a > 0.0f) || (order >= MC_COG_N / 2u)) {
        return MC_COG_ST_ARG;
    }
    for (uint32_t k = 0u; k < MC_COG_N; ++k) {
        if (!mc_isfinite_f32(i_q_a[k]) || (mc_abs_f32(i_q_a[k]) > 1.0e6f)) {
            return MC_COG_ST_NONFINITE; /* 1e6 A: the sum below stays finite */
        }
        sum += i_q_a[k];
    }
    mean = sum / (float)MC_COG_N;
    kept_orders(i_q_a, NULL, order, count, a, b);
    for (uint32_t k = 0u; k < MC_COG_N; ++k) {
        const float v = mc_abs_f32(kept_value(i_q_a, k, mean, order, count, a, b));
        fs = (v > fs) ? v : fs;
    }
    if (fs > i_bound_a) {
        return MC_COG_ST_AMPLITUDE;
    }
    map->magic = MC_COG_MAGIC;
    map->format = MC_COG_FORMAT | (MC_COG_N << 16);
    map->ident = *ident;
    map->scale_a = fs / 32767.0f;
    map->order = order;
    inv = (fs > 0.0f) ? (32767.0f / fs) : 0.0f;
    for (uint32_t k = 0u; k < MC_COG_N; ++k) {
        map->q[k] = round_q15(kept_value(i_q_a, k, mean, order, count, a, b) * inv);
    }
    map->crc = mc_cog_crc(map);
    return MC_COG_ST_OK;
}

mc_cog_status_t mc_cog_check(const mc_cog_map_t *map, const mc_cog_ident_t *ident)
{
    float d;
    if (map == NULL) {
        return MC_COG_ST_EMPTY;
    }
    if (!ident_valid(ident)) {
        return MC_COG_ST_ENCODER; /* the drive has no encoder a map fits */
    }
    if ((map->magic != MC_COG_MAGIC) || (map->format != (MC_COG_FORMAT | (MC_COG_N << 16)))) {
        return MC_COG_ST_LAYOUT;
    }
    if (mc_cog_crc(map) != map->crc) {
        return MC_COG_ST_CRC;
    }
    if (!mc_isfinite_f32(map->scale_a) || !(map->scale_a >= 0.0f) || !ident_valid(&map->ident) ||
        (map->order >= MC_COG_N / 2u)) {
        return MC_COG_ST_LAYOUT;
    }
    if ((map->ident.enc_type != ident->enc_type) || (map->ident.enc_cpr != ident->enc_cpr) ||
        (map->ident.enc_reversed != ident->enc_reversed) ||
        (map->ident.pole_pairs != ident->pole_pairs)) {
        return MC_COG_ST_ENCODER;
    }
    /* both offsets within +-4 pi (ident_valid): the difference within
     * +-8 pi, wrapped into (-pi, pi] in at most four turns */
    d = map->ident.enc_offset_rad - ident->enc_offset_rad;
    for (uint32_t i = 0u; (i < 4u) && (d > COG_PI); ++i) {
        d -= COG_TWO_PI;
    }
    for (uint32_t i = 0u; (i < 4u) && (d <= -COG_PI); ++i) {
        d += COG_TWO_PI;
    }
    if (mc_abs_f32(d) / (float)ident->pole_pairs > MC_COG_OFFSET_TOL_M_RAD) {
        return MC_COG_ST_ENCODER;
    }
    return MC_COG_ST_OK;
}

float mc_cog_ff_a(const mc_cog_map_t *map, float theta_m_rad)
{
    float x = theta_m_rad * COG_BIN_PER_R;
    int32_t i;
    uint32_t k;
    float f;
    float a;
    float b;
    if (!(x >= 0.0f) || !(x < (float)MC_COG_N)) {
        /* off [0, 2 pi): the drive's angle never is; wrap any finite one */
        if (!mc_isfinite_f32(x) || (mc_abs_f32(x) > 1.0e9f)) {
            return 0.0f;
        }
        x -= (float)MC_COG_N * (float)(int32_t)(x * (1.0f / (float)MC_COG_N));
        x = (x < 0.0f) ? (x + (float)MC_COG_N) : x;
    }
    i = (int32_t)x;
    f = x - (float)i;
    k = (uint32_t)i & (MC_COG_N - 1u);
    a = (float)map->q[k];
    b = (float)map->q[(k + 1u) & (MC_COG_N - 1u)];
    return map->scale_a * (a + (f * (b - a)));
}

float mc_cog_ff_adv_a(const mc_cog_map_t *map, float theta_m_rad, float rate_rad_s,
                      const mc_cog_loop_t *lp, float *p_i_a)
{
    const float h = 1.0f / COG_BIN_PER_R;
    const float th_d = theta_m_rad + (rate_rad_s * lp->lead_d_s);
    const float i = mc_cog_ff_a(map, theta_m_rad + (rate_rad_s * lp->lead_i_s));
    const float i0 = mc_cog_ff_a(map, th_d - (0.5f * h));
    const float i1 = mc_cog_ff_a(map, th_d + (0.5f * h));
    *p_i_a = i;
    return i + (lp->tau_s * rate_rad_s * (i1 - i0) * COG_BIN_PER_R);
}

void mc_cog_series_init(mc_cog_series_t *s, const mc_cog_map_t *map)
{
    s->order = map->order;
    s->count = mc_cog_keep_count(map->order);
    for (uint32_t m = 0u; m < MC_COG_KEEP_MAX; ++m) {
        s->a[m] = 0.0f;
        s->b[m] = 0.0f;
    }
    kept_orders(NULL, map, s->order, s->count, s->a, s->b);
}

/* The fade of a term whose frequency is x times the current loop's
 * bandwidth (mc_drive_cog.h): 1 up to MC_COG_FADE_START, 0 from
 * MC_COG_FADE_END, linear between. */
static float fade(float x)
{
    const float g = (MC_COG_FADE_END - x) * (1.0f / (MC_COG_FADE_END - MC_COG_FADE_START));
    return (g >= 1.0f) ? 1.0f : ((g > 0.0f) ? g : 0.0f);
}

/* The series' terms at the angle theta [rad], each faded by its frequency
 * (x1 >= 0: the first term's, over the loop's bandwidth), in one pass with
 * one sine and cosine: returns their sum, and *p_d their derivative in angle
 * at theta + delta. That derivative is a Taylor step from theta with the
 * first three derivatives there, V'(theta + delta) ~ V' + delta V'' +
 * delta^2 / 2 V''': for a term of order j and amplitude A it errs by at most
 * j A p^3 / 6, p = j |delta| its phase step (the Lagrange remainder, |V''''|
 * <= j^4 A): with the drive's leads (delta = rate T / 2) a factor p below
 * the loop model's own, its derivative at mid-period for the difference
 * over the period, sin(p) / p ~ 1 - p^2 / 6 of it (mc_cog_loop_t). Both 0
 * for an angle whose order-fold is not finite or beyond 1e6 turns (a
 * non-finite rate makes the angle so). The terms past the fade's end are
 * not evaluated. */
static float series_at(const mc_cog_series_t *s, float theta, float delta, float x1, float *p_d)
{
    /* order theta in turns, its fraction: for the drive's angle in
     * [0, 2 pi) plus a lead, below order + 1 turns, where float's rounding
     * is under 6e-5 of a period (order < 512) */
    const float u0 = theta * ((float)s->order / COG_TWO_PI);
    float v = 0.0f;  /* the sum */
    float d1 = 0.0f; /* its derivatives in angle at theta: V' */
    float d2 = 0.0f; /* -V'' */
    float d3 = 0.0f; /* -V''' */
    *p_d = 0.0f;
    if (!mc_isfinite_f32(u0) || (mc_abs_f32(u0) > 1.0e6f)) {
        return 0.0f;
    }
    float u = u0 - (float)(int32_t)u0;
    u = (u < 0.0f) ? (u + 1.0f) : u;
    float s1;
    float c1;
    mc_sincos_f32(u * COG_TWO_PI, &s1, &c1);
    float sn = s1;
    float cs = c1;
    float xm = 0.0f;                     /* this term's frequency over the bandwidth */
    float jm = 0.0f;                     /* and its order */
    const float order = (float)s->order; /* < 512: the sums below are exact */
    for (uint32_t m = 0u; m < s->count; ++m) {
        xm += x1;
        jm += order;
        /* a cos + b sin of j theta, and its derivative over j, b cos - a sin */
        float t = (s->a[m] * cs) + (s->b[m] * sn);
        float w = (s->b[m] * cs) - (s->a[m] * sn);
        if (xm > MC_COG_FADE_START) {
            const float g = fade(xm);
            if (!(g > 0.0f)) {
                break; /* this term and every higher one faded out */
            }
            t *= g;
            w *= g;
        }
        const float jw = jm * w; /* the term's V'; -V'' = j^2 t, -V''' = j^2 jw */
        const float j2 = jm * jm;
        v += t;
        d1 += jw;
        d2 += j2 * t;
        d3 += j2 * jw;
        const float c_next = (cs * c1) - (sn * s1); /* cos, sin of (m + 2) x */
        sn = (sn * c1) + (cs * s1);
        cs = c_next;
    }
    *p_d = d1 - (delta * (d2 + (0.5f * delta * d3)));
    return v;
}

float mc_cog_series_ff_adv_a(const mc_cog_series_t *s, float theta_m_rad, float rate_rad_s,
                             const mc_cog_loop_t *lp, float *p_i_a)
{
    /* the first term's frequency over the loop's bandwidth (NaN for a
     * non-finite rate: so is the angle, and the result is 0) */
    const float x1 = mc_abs_f32(rate_rad_s) * lp->tau_s * (float)s->order;
    float di;
    const float i = series_at(s, theta_m_rad + (rate_rad_s * lp->lead_i_s),
                              rate_rad_s * (lp->lead_d_s - lp->lead_i_s), x1, &di);
    *p_i_a = i;
    return mc_isfinite_f32(rate_rad_s) ? (i + (lp->tau_s * rate_rad_s * di)) : 0.0f;
}

float mc_cog_map_order_rms(const mc_cog_map_t *map)
{
    float sq = 0.0f;
    float dq = 0.0f;
    for (uint32_t k = 0u; k < MC_COG_N; ++k) {
        const float a = (float)map->q[k];
        const float d = (float)map->q[(k + 1u) & (MC_COG_N - 1u)] - a;
        sq += a * a;
        dq += d * d;
    }
    return (sq > 0.0f) ? (COG_BIN_PER_R * mc_sqrt_f32(dq / sq)) : 0.0f;
}

float mc_cog_fade_gain(float x)
{
    return fade(x);
}

/* The power of order k's line in x[0..N) less its mean (Goertzel):
 * |X_k|^2 N^-2 4, the squared amplitude of a sinusoid of that order. */
static float line_power(const float *x, float mean, uint32_t k)
{
    float sn;
    float cs;
    mc_sincos_f32((float)k / COG_BIN_PER_R, &sn, &cs);
    const float c2 = 2.0f * cs;
    float s1 = 0.0f;
    float s2 = 0.0f;
    for (uint32_t i = 0u; i < MC_COG_N; ++i) {
        const float s0 = (x[i] - mean) + (c2 * s1) - s2;
        s2 = s1;
        s1 = s0;
    }
    const float p = (s1 * s1) + (s2 * s2) - (c2 * s1 * s2);
    return p * (4.0f / ((float)MC_COG_N * (float)MC_COG_N));
}

uint32_t mc_cog_find_order(const float *i_q_a, uint32_t n, uint32_t pole_pairs)
{
    uint32_t seen[MC_COG_N / 64u] = {0u}; /* the orders tried, one bit each */
    uint32_t best = 0u;
    float best_p = 0.0f;
    float mean = 0.0f;
    float var = 0.0f;
    if ((i_q_a == NULL) || (n != MC_COG_N)) {
        return 0u;
    }
    for (uint32_t i = 0u; i < MC_COG_N; ++i) {
        if (!mc_isfinite_f32(i_q_a[i])) {
            return 0u;
        }
        mean += i_q_a[i];
    }
    mean *= 1.0f / (float)MC_COG_N;
    for (uint32_t i = 0u; i < MC_COG_N; ++i) {
        var += (i_q_a[i] - mean) * (i_q_a[i] - mean);
    }
    for (uint32_t q = 3u; q <= 1000u; q += 3u) {
        const uint32_t o = mc_cog_order(q, pole_pairs);
        if ((o == 0u) || ((seen[o / 32u] >> (o % 32u)) & 1u) != 0u) {
            continue;
        }
        seen[o / 32u] |= 1u << (o % 32u);
        const float p = line_power(i_q_a, mean, o);
        if (p > best_p) {
            best_p = p;
            best = o;
        }
    }
    /* the mean power per order: the variance's 2 / N of the squared
     * amplitudes summed over the N / 2 - 1 orders (Parseval) */
    const uint32_t n_orders = (MC_COG_N / 2u) - 1u; /* 511: exact */
    const float per_order = 2.0f * (var / (float)MC_COG_N) / (float)n_orders;
    return (best_p >= MC_COG_FIND_SNR * per_order) && (best_p > 0.0f) ? best : 0u;
}
