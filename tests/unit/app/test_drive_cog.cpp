// The anticogging map (firmware/app/drive/mc_drive_cog.h): the builder from
// a calibration's N currents, the validation against the drive's encoder,
// the interpolated lookup, against analytic values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

extern "C" {
#include "mc_drive_cog.h"
}

namespace
{

constexpr double kPi = 3.14159265358979323846;
constexpr uint32_t kN = MC_COG_N;

mc_cog_ident_t ident()
{
    mc_cog_ident_t id{};
    id.enc_type = 0u;
    id.enc_cpr = 8192u;
    id.enc_reversed = 0u;
    id.pole_pairs = 7u;
    id.enc_offset_rad = 1.25f;
    return id;
}

// amp sin(k theta + phase) + mean at the N bins.
std::vector<float> sinusoid(double amp, uint32_t k, double phase, double mean)
{
    std::vector<float> v(kN);
    for (uint32_t i = 0; i < kN; ++i) {
        v[i] = static_cast<float>(mean + amp * std::sin(k * (2.0 * kPi * i / kN) + phase));
    }
    return v;
}

mc_cog_map_t built(const std::vector<float> &v, float bound = 10.0f)
{
    mc_cog_map_t m{};
    const mc_cog_ident_t id = ident();
    EXPECT_EQ(mc_cog_build(&m, v.data(), kN, &id, bound, 0u), MC_COG_ST_OK);
    return m;
}

// Largest |lookup - amp sin(k theta + phase)| over 16 points per bin.
double max_interp_error(const mc_cog_map_t &m, double amp, uint32_t k, double phase)
{
    double e = 0.0;
    for (uint32_t j = 0; j < 16u * kN; ++j) {
        const double th = 2.0 * kPi * j / (16.0 * kN);
        const double want = amp * std::sin(k * th + phase);
        e = std::max(e, std::fabs(mc_cog_ff_a(&m, static_cast<float>(th)) - want));
    }
    return e;
}

// A map of 0.2 sin(84 theta) [A] built with its order, and its series.
void order84(mc_cog_map_t *m, mc_cog_series_t *ser)
{
    const std::vector<float> v = sinusoid(0.2, 84u, 0.0, 0.0);
    const mc_cog_ident_t id = ident();
    ASSERT_EQ(mc_cog_build(m, v.data(), kN, &id, 10.0f, 84u), MC_COG_ST_OK);
    mc_cog_series_init(ser, m);
}

} // namespace

// Linear interpolation of a sinusoid of order k at spacing h = 2 pi / N
// errs by at most amp (k h)^2 / 8 (|f''| <= amp k^2, the remainder h^2/8
// |f''|); q15 adds half an LSB of the full scale (amp / 32767 / 2) and
// float arithmetic a few 1e-7 of it: the bound asserted is
// amp ((k h)^2 / 8 + 1 / 65534 + 1e-6). The error also reaches half the
// interpolation term for k = 84 (the peak falls between two bins for some
// phase): the test sees the interpolation, not a lucky grid.
TEST(DriveCog, InterpolationErrorOfASinusoidWithinTheDerivedBound)
{
    const double amp = 0.8;
    for (const uint32_t k : {1u, 12u, 42u, 84u}) {
        const double phase = 0.3;
        const mc_cog_map_t m = built(sinusoid(amp, k, phase, 0.0));
        const double h = 2.0 * kPi / kN;
        const double interp = amp * (k * h) * (k * h) / 8.0;
        const double bound = interp + amp * (1.0 / 65534.0 + 1e-6);
        const double e = max_interp_error(m, amp, k, phase);
        EXPECT_LE(e, bound) << "k " << k;
        if (k == 84u) {
            EXPECT_GE(e, 0.5 * interp) << "k " << k;
        }
    }
}

// At the bins the map returns the entries (less the mean), to q15: half an
// LSB of the full scale (0.8 A / 65534) plus float rounding (1e-6 A).
TEST(DriveCog, TheMeanIsRemovedAndTheBinsAreExact)
{
    const std::vector<float> v = sinusoid(0.8, 12u, 0.0, 3.0);
    const mc_cog_map_t m = built(v);
    for (uint32_t i = 0; i < kN; i += 37u) {
        const float th = static_cast<float>(2.0 * kPi * i / kN);
        EXPECT_NEAR(mc_cog_ff_a(&m, th), v[i] - 3.0, 0.8 / 65534.0 + 1e-6) << i;
    }
    EXPECT_NEAR(m.scale_a * 32767.0f, 0.8f, 1e-6f); // the full scale is the largest |entry|
}

// Between bin N-1 and 2 pi the lookup interpolates to bin 0; any finite
// angle is wrapped (negative, beyond 2 pi); a non-finite one gives 0.
// Entries: bin 0 = +1 A, bin N-1 = -1 A, the rest 0: the midpoint is 0 and
// a quarter of the way from N-1 is -0.5 A (exact in q15: +-32767; float
// rounding of the angle 1e-3 A at most, an angle error of 1e-3 bins).
TEST(DriveCog, WrapsAroundTwoPi)
{
    std::vector<float> v(kN, 0.0f);
    v[0] = 1.0f;
    v[kN - 1u] = -1.0f;
    const mc_cog_map_t m = built(v);
    const double h = 2.0 * kPi / kN;
    EXPECT_NEAR(mc_cog_ff_a(&m, static_cast<float>(2.0 * kPi - 0.5 * h)), 0.0, 1e-3);
    EXPECT_NEAR(mc_cog_ff_a(&m, static_cast<float>(2.0 * kPi - 0.75 * h)), -0.5, 1e-3);
    EXPECT_NEAR(mc_cog_ff_a(&m, static_cast<float>(-0.5 * h)), 0.0, 1e-3);
    EXPECT_NEAR(mc_cog_ff_a(&m, static_cast<float>(-0.25 * h)), 0.5, 1e-3);
    EXPECT_NEAR(mc_cog_ff_a(&m, static_cast<float>(4.0 * kPi)), 1.0, 1e-3);
    EXPECT_NEAR(mc_cog_ff_a(&m, static_cast<float>(2.0 * kPi + 0.5 * h)), 0.5, 1e-3);
    EXPECT_EQ(mc_cog_ff_a(&m, NAN), 0.0f);
    EXPECT_EQ(mc_cog_ff_a(&m, INFINITY), 0.0f);
}

// Refusals of the builder, each named, and the map left as it was.
TEST(DriveCog, BuilderRefusesBadInputAndChangesNothing)
{
    const mc_cog_map_t good = built(sinusoid(0.5, 12u, 0.0, 0.0));
    const mc_cog_ident_t id = ident();
    mc_cog_map_t m = good;
    std::vector<float> v = sinusoid(0.5, 12u, 0.0, 0.0);
    v[100] = NAN;
    EXPECT_EQ(mc_cog_build(&m, v.data(), kN, &id, 10.0f, 0u), MC_COG_ST_NONFINITE);
    v[100] = INFINITY;
    EXPECT_EQ(mc_cog_build(&m, v.data(), kN, &id, 10.0f, 0u), MC_COG_ST_NONFINITE);
    // amplitude: 0.5 A about the mean; a bound of 0.49 A refuses, 0.51 A takes it
    v = sinusoid(0.5, 12u, 0.0, 2.0);
    EXPECT_EQ(mc_cog_build(&m, v.data(), kN, &id, 0.49f, 0u), MC_COG_ST_AMPLITUDE);
    EXPECT_EQ(mc_cog_build(&m, v.data(), kN - 1u, &id, 10.0f, 0u), MC_COG_ST_ARG);
    EXPECT_EQ(mc_cog_build(&m, v.data(), kN, &id, 0.0f, 0u), MC_COG_ST_ARG);
    EXPECT_EQ(mc_cog_build(&m, v.data(), kN, &id, NAN, 0u), MC_COG_ST_ARG);
    EXPECT_EQ(mc_cog_build(&m, nullptr, kN, &id, 10.0f, 0u), MC_COG_ST_ARG);
    EXPECT_EQ(mc_cog_build(&m, v.data(), kN, nullptr, 10.0f, 0u), MC_COG_ST_ARG);
    mc_cog_ident_t bad = id;
    bad.enc_cpr = 0u;
    EXPECT_EQ(mc_cog_build(&m, v.data(), kN, &bad, 10.0f, 0u), MC_COG_ST_ARG);
    EXPECT_EQ(std::memcmp(&m, &good, sizeof m), 0);
    EXPECT_EQ(mc_cog_build(&m, v.data(), kN, &id, 0.51f, 0u), MC_COG_ST_OK);
}

// Validation: another layout, a broken CRC, another encoder; an offset
// within half a bin (pi / N mechanical, 7 pole pairs: 0.0215 rad el.) is
// the same mounting, beyond it is not; the wrap of the offset at 2 pi.
TEST(DriveCog, ValidationNamesWhatIsWrong)
{
    const mc_cog_map_t good = built(sinusoid(0.5, 12u, 0.0, 0.0));
    const mc_cog_ident_t id = ident();
    EXPECT_EQ(mc_cog_check(&good, &id), MC_COG_ST_OK);
    EXPECT_EQ(mc_cog_check(nullptr, &id), MC_COG_ST_EMPTY);

    mc_cog_map_t m = good;
    m.magic ^= 1u;
    EXPECT_EQ(mc_cog_check(&m, &id), MC_COG_ST_LAYOUT);
    m = good;
    m.format = MC_COG_FORMAT | (512u << 16);
    EXPECT_EQ(mc_cog_check(&m, &id), MC_COG_ST_LAYOUT);
    m = good;
    m.format = (MC_COG_FORMAT + 1u) | (kN << 16);
    EXPECT_EQ(mc_cog_check(&m, &id), MC_COG_ST_LAYOUT);
    m = good;
    m.q[500] ^= 4;
    EXPECT_EQ(mc_cog_check(&m, &id), MC_COG_ST_CRC);
    m = good;
    m.scale_a = -1.0f;
    m.crc = mc_cog_crc(&m);
    EXPECT_EQ(mc_cog_check(&m, &id), MC_COG_ST_LAYOUT);
    // an order the map cannot hold one period of (N / 2 and beyond)
    m = good;
    m.order = kN / 2u;
    m.crc = mc_cog_crc(&m);
    EXPECT_EQ(mc_cog_check(&m, &id), MC_COG_ST_LAYOUT);
    m.order = kN / 2u - 1u;
    m.crc = mc_cog_crc(&m);
    EXPECT_EQ(mc_cog_check(&m, &id), MC_COG_ST_OK);

    mc_cog_ident_t other = id;
    other.enc_cpr = 4096u;
    EXPECT_EQ(mc_cog_check(&good, &other), MC_COG_ST_ENCODER);
    other = id;
    other.enc_type = 1u;
    EXPECT_EQ(mc_cog_check(&good, &other), MC_COG_ST_ENCODER);
    other = id;
    other.enc_reversed = 1u;
    EXPECT_EQ(mc_cog_check(&good, &other), MC_COG_ST_ENCODER);
    other = id;
    other.pole_pairs = 4u;
    EXPECT_EQ(mc_cog_check(&good, &other), MC_COG_ST_ENCODER);
    const float tol_e = static_cast<float>(kPi / kN * 7.0); // half a bin, electrical
    other = id;
    other.enc_offset_rad = id.enc_offset_rad + 0.9f * tol_e;
    EXPECT_EQ(mc_cog_check(&good, &other), MC_COG_ST_OK);
    other.enc_offset_rad = id.enc_offset_rad - 1.1f * tol_e;
    EXPECT_EQ(mc_cog_check(&good, &other), MC_COG_ST_ENCODER);
    // 1.25 rad and 1.25 - 2 pi are the same electrical angle
    other.enc_offset_rad = id.enc_offset_rad - static_cast<float>(2.0 * kPi);
    EXPECT_EQ(mc_cog_check(&good, &other), MC_COG_ST_OK);
}

// The cogging order lcm(slots, 2 p) (mc_cog_order) and the orders a map
// built with it keeps.
TEST(DriveCog, CoggingOrderIsLcmOfSlotsAndPoles)
{
    EXPECT_EQ(mc_cog_order(12u, 7u), 84u);   // 12N14P (the SK3)
    EXPECT_EQ(mc_cog_order(24u, 11u), 264u); // 24N22P (the GM4108)
    EXPECT_EQ(mc_cog_order(9u, 3u), 18u);
    EXPECT_EQ(mc_cog_order(0u, 7u), 0u); // unknown: every order
    EXPECT_EQ(mc_cog_order(12u, 0u), 0u);
    EXPECT_EQ(mc_cog_order(1001u, 7u), 0u); // out of range
    EXPECT_EQ(mc_cog_order(36u, 20u), 360u);
    EXPECT_EQ(mc_cog_order(50u, 28u), 0u); // lcm 1400: not below N / 2
    EXPECT_EQ(mc_cog_keep_count(0u), 0u);
    EXPECT_EQ(mc_cog_keep_count(84u), 6u); // 84 .. 504 < 512
    EXPECT_EQ(mc_cog_keep_count(264u), 1u);
    EXPECT_EQ(mc_cog_keep_count(1u), MC_COG_KEEP_MAX);
}

// A map built with order 84 keeps orders 84 and 168 of the currents and
// drops the calibration's noise at other orders (14, 37, 85) and the mean.
TEST(DriveCog, FilteredMapKeepsOnlyTheMultiplesOfTheOrder)
{
    std::vector<float> v = sinusoid(0.8, 84u, 0.3, 0.25);
    const std::vector<float> h2 = sinusoid(0.1, 168u, -1.0, 0.0);
    const std::vector<float> n14 = sinusoid(0.2, 14u, 0.7, 0.0);
    const std::vector<float> n37 = sinusoid(0.15, 37u, 2.0, 0.0);
    const std::vector<float> n85 = sinusoid(0.05, 85u, 1.0, 0.0);
    for (uint32_t i = 0; i < kN; ++i) {
        v[i] += h2[i] + n14[i] + n37[i] + n85[i];
    }
    mc_cog_map_t m{};
    const mc_cog_ident_t id = ident();
    ASSERT_EQ(mc_cog_build(&m, v.data(), kN, &id, 10.0f, 84u), MC_COG_ST_OK);
    double e = 0.0;
    for (uint32_t i = 0; i < kN; ++i) {
        const double th = 2.0 * kPi * i / kN;
        const double want = 0.8 * std::sin(84.0 * th + 0.3) + 0.1 * std::sin(168.0 * th - 1.0);
        e = std::max(e, std::fabs(m.q[i] * static_cast<double>(m.scale_a) - want));
    }
    // Tolerance: at the bins the projection is exact; what is left is
    // float's sums over 1024 bins (~1e-5 of the 1.4 A full scale), the
    // sine's error (mc_sincos_f32, ~1e-6) and q15's half LSB (1.4 A / 65534
    // = 2.1e-5): 1e-4 A, far below the 0.05 A of the smallest dropped order.
    EXPECT_LT(e, 1e-4);
    // The same currents with order 0 keep everything but the mean.
    ASSERT_EQ(mc_cog_build(&m, v.data(), kN, &id, 10.0f, 0u), MC_COG_ST_OK);
    e = 0.0;
    for (uint32_t i = 0; i < kN; ++i) {
        e = std::max(e, std::fabs(m.q[i] * static_cast<double>(m.scale_a) - (v[i] - 0.25)));
    }
    EXPECT_LT(e, 1e-4);
    // An order whose period the map cannot hold is refused, the map kept.
    const mc_cog_map_t before = m;
    EXPECT_EQ(mc_cog_build(&m, v.data(), kN, &id, 10.0f, kN / 2u), MC_COG_ST_ARG);
    EXPECT_EQ(std::memcmp(&m, &before, sizeof m), 0);
}

// The series of a filtered map (mc_cog_series_init, mc_cog_series_ff_adv_a):
// the builder stores its order; the series' value anywhere, not only at the
// bins, is the kept orders' sinusoids, where the bins' interpolation loses
// cos(pi k / N) at mid-bin (0.69 at k = 264). Tolerance 2e-4 A: the
// projection's float sums and q15's half LSB (1e-4 A at the bins, the
// test above) plus the series' phase, order theta in float turns (6e-5 of
// a period at k = 264: 4e-4 rad of 0.3 A = 1.1e-4 A) and mc_sincos_f32.
TEST(DriveCog, SeriesOfAFilteredMapIsExactBetweenTheBins)
{
    std::vector<float> v = sinusoid(0.3, 264u, 0.4, 0.1);
    const std::vector<float> n = sinusoid(0.05, 100u, 1.0, 0.0); // dropped
    for (uint32_t i = 0; i < kN; ++i) {
        v[i] += n[i];
    }
    mc_cog_map_t m{};
    const mc_cog_ident_t id = ident();
    ASSERT_EQ(mc_cog_build(&m, v.data(), kN, &id, 10.0f, 264u), MC_COG_ST_OK);
    EXPECT_EQ(m.order, 264u);
    EXPECT_EQ(mc_cog_check(&m, &id), MC_COG_ST_OK);
    mc_cog_series_t ser{};
    mc_cog_series_init(&ser, &m);
    EXPECT_EQ(ser.order, 264u);
    EXPECT_EQ(ser.count, 1u); // 528 is not below N / 2
    const mc_cog_loop_t still = {0.0f, 0.0f, 0.0f};
    double e_ser = 0.0;
    double e_bins = 0.0;
    for (uint32_t j = 0; j < 8u * kN; ++j) {
        const double th = 2.0 * kPi * (j + 0.5) / (8.0 * kN);
        const double want = 0.3 * std::sin(264.0 * th + 0.4);
        float i_a = 0.0f;
        const float r = mc_cog_series_ff_adv_a(&ser, static_cast<float>(th), 0.0f, &still, &i_a);
        EXPECT_EQ(r, i_a); // no rate: the reference is the current
        e_ser = std::max(e_ser, std::fabs(i_a - want));
        e_bins = std::max(e_bins, std::fabs(mc_cog_ff_a(&m, static_cast<float>(th)) - want));
    }
    EXPECT_LT(e_ser, 2e-4);
    // the bins' interpolation of the same map: the mid-bin loss, 0.31 of
    // 0.3 A (1 - cos(pi 264 / 1024)) at the crests, less between
    EXPECT_GT(e_bins, 0.05);
    // a map of order 0 has no series: the drive interpolates its bins
    ASSERT_EQ(mc_cog_build(&m, v.data(), kN, &id, 10.0f, 0u), MC_COG_ST_OK);
    mc_cog_series_init(&ser, &m);
    EXPECT_EQ(ser.count, 0u);
}

// The feed-forward through the current loop (mc_cog_loop_t): the current at
// lead_i, plus tau times its rate of change at lead_d, the derivative in
// angle exact; the bins' pair the same to their interpolation. For
// I = A sin(k th): r = A sin(k (th + w lead_i)) + tau w A k cos(k (th + w
// lead_d)). Tolerances: the series as above scaled by the derivative's
// gain tau w k (2.5 here): 1e-3 A; the bins: (k h)^2 / 8 of the amplitude
// (3.4 % at k = 84) on the current and the slope's half-bin difference
// (1 - sinc, 1.1 %) on the derivative term: 0.05 of the 0.8 A reference
// scale.
TEST(DriveCog, FeedForwardLeadsTheCurrentAndItsRateOfChange)
{
    mc_cog_map_t m{};
    mc_cog_series_t ser{};
    ASSERT_NO_FATAL_FAILURE(order84(&m, &ser));
    const mc_cog_loop_t lp = {3.3e-5f, 5.0e-5f, 4.0e-4f};
    const double w = 60.0; // rad/s: the SK3 at 10 % of its rated speed
    for (uint32_t j = 0; j < 97u; ++j) {
        const double th = 0.013 + 2.0 * kPi * j / 97.0;
        const double xi = 84.0 * (th + w * lp.lead_i_s);
        const double xd = 84.0 * (th + w * lp.lead_d_s);
        const double want_i = 0.2 * std::sin(xi);
        const double want = want_i + lp.tau_s * w * 0.2 * 84.0 * std::cos(xd);
        float i_a = 0.0f;
        const float r =
            mc_cog_series_ff_adv_a(&ser, static_cast<float>(th), static_cast<float>(w), &lp, &i_a);
        EXPECT_NEAR(i_a, want_i, 2e-4) << j;
        EXPECT_NEAR(r, want, 1e-3) << j;
        const float rb =
            mc_cog_ff_adv_a(&m, static_cast<float>(th), static_cast<float>(w), &lp, &i_a);
        EXPECT_NEAR(rb, want, 0.05 * 0.8) << j;
    }
    float i_a = 1.0f;
    EXPECT_EQ(mc_cog_series_ff_adv_a(&ser, NAN, 1.0f, &lp, &i_a), 0.0f);
    EXPECT_EQ(mc_cog_series_ff_adv_a(&ser, 1.0f, INFINITY, &lp, &i_a), 0.0f);
}

namespace
{

// A map of the given order built from sinusoids amp[n] sin((n + 1) order
// theta + n), and its series.
void built_series(uint32_t order, const std::vector<double> &amp, mc_cog_map_t *m,
                  mc_cog_series_t *ser)
{
    std::vector<float> v(kN, 0.0f);
    for (uint32_t n = 0; n < amp.size(); ++n) {
        const std::vector<float> h = sinusoid(amp[n], (n + 1u) * order, n, 0.0);
        for (uint32_t i = 0; i < kN; ++i) {
            v[i] += h[i];
        }
    }
    const mc_cog_ident_t id = ident();
    ASSERT_EQ(mc_cog_build(m, v.data(), kN, &id, 10.0f, order), MC_COG_ST_OK);
    mc_cog_series_init(ser, m);
    ASSERT_EQ(ser->count, amp.size());
}

// The series feed-forward in double, each term faded as the firmware fades
// it: the current at lead_i, the reference with the derivative at lead_d
// (r), the same with the derivative taken at lead_i (r_at_i: what the test
// must tell from r), and the tolerance on r (below).
struct SeriesRef {
    double i;
    double r;
    double r_at_i;
    double tol_i;
    double tol_r;
};

// Float's phase error of a term of order j [rad] (mc_cog_series_ff_adv_a
// in float): the angle theta + w lead_i (< 2 pi + lead) to half an ulp,
// 2.4e-7 rad, times j; order theta / 2 pi in float turns (below order + 1
// < 512 turns: half an ulp, 1.5e-5 turns at order 264, 9.6e-5 rad, 3.6e-7
// per unit of order) and the rounding of order / 2 pi (6e-8 of order + 1
// turns: 3.8e-7 rad per unit of order); the fundamental's phase is
// multiplied by the harmonic's index. Sum 1e-6 j, taken as 1.5e-6 j, plus
// the angle-addition recursion's and mc_sincos_f32's rounding, a few 1e-7
// per step over at most 8 steps: 3e-6.
double phase_error(double j)
{
    return (1.5e-6 * j) + 3e-6;
}

SeriesRef series_ref(const mc_cog_series_t &s, float th_f, float w_f, const mc_cog_loop_t &lp)
{
    const double th = th_f;
    const double w = w_f;
    const double tau = lp.tau_s;
    const double delta = w * (static_cast<double>(lp.lead_d_s) - lp.lead_i_s);
    const double x1 = std::fabs(w) * tau * s.order;
    SeriesRef ref{0.0, 0.0, 0.0, 1e-6, 1e-6}; // 1e-6 A: float's sums
    double di = 0.0;
    double di_at_i = 0.0;
    for (uint32_t m = 0; m < s.count; ++m) {
        const double j = (m + 1.0) * s.order;
        const double x = (m + 1.0) * x1;
        const double g =
            std::min(1.0, (MC_COG_FADE_END - x) /
                              (static_cast<double>(MC_COG_FADE_END) - MC_COG_FADE_START));
        if (!(g > 0.0)) {
            break;
        }
        const double a = s.a[m];
        const double b = s.b[m];
        const double amp = std::hypot(a, b);
        const double xi = j * (th + w * lp.lead_i_s);
        const double xd = j * (th + w * lp.lead_d_s);
        ref.i += g * (a * std::cos(xi) + b * std::sin(xi));
        di += g * j * (b * std::cos(xd) - a * std::sin(xd));
        di_at_i += g * j * (b * std::cos(xi) - a * std::sin(xi));
        // the Taylor step's remainder: j A p^3 / 6 of the derivative, p =
        // j |delta| (|V''''| <= j^4 A), times tau |w| in the reference;
        // float's phase error on the current and on the derivative term
        // (x = tau |w| j of the amplitude)
        const double p = j * std::fabs(delta);
        const double e = g * amp * phase_error(j);
        ref.tol_i += e;
        ref.tol_r += (tau * std::fabs(w) * g * j * amp * p * p * p / 6.0) + (e * (1.0 + x));
    }
    ref.r = ref.i + tau * w * di;
    ref.r_at_i = ref.i + tau * w * di_at_i;
    return ref;
}

// Over a sweep of speeds (both signs) from 0 to past the fade's end and
// angles around the turn: the largest error over its tolerance, and the
// largest miss of the derivative taken at lead_i over the same tolerance.
struct SweepResult {
    double worst_i;      // max |i - ref.i| / ref.tol_i
    double worst_r;      // max |r - ref.r| / ref.tol_r
    double at_i_miss;    // max |ref.r_at_i - ref.r| / ref.tol_r
    double err_r_rel;    // max |r - ref.r| over max |ref.r|
    double x_of_worst_r; // the fundamental's x where worst_r is
};

SweepResult sweep(const mc_cog_series_t &s, const mc_cog_loop_t &lp)
{
    SweepResult res{0.0, 0.0, 0.0, 0.0, 0.0};
    double err_r = 0.0;
    double ref_max = 0.0;
    for (int32_t k = -34; k <= 34; ++k) { // x1 = 0.25 k: to 8.5, past the end
        const double x1 = 0.25 * k;
        const float w = static_cast<float>(x1 / (lp.tau_s * s.order));
        for (uint32_t n = 0; n < 41u; ++n) {
            const float th = static_cast<float>(0.011 + 2.0 * kPi * n / 41.0);
            const SeriesRef ref = series_ref(s, th, w, lp);
            float i_a = 1.0f;
            const float r = mc_cog_series_ff_adv_a(&s, th, w, &lp, &i_a);
            res.worst_i = std::max(res.worst_i, std::fabs(i_a - ref.i) / ref.tol_i);
            const double q = std::fabs(r - ref.r) / ref.tol_r;
            if (q > res.worst_r) {
                res.worst_r = q;
                res.x_of_worst_r = x1;
            }
            res.at_i_miss = std::max(res.at_i_miss, std::fabs(ref.r_at_i - ref.r) / ref.tol_r);
            err_r = std::max(err_r, std::fabs(r - ref.r));
            ref_max = std::max(ref_max, std::fabs(ref.r));
        }
    }
    res.err_r_rel = err_r / ref_max;
    return res;
}

} // namespace

// The series feed-forward's one pass (mc_cog_series_ff_adv_a): the current
// at lead_i, and the derivative at lead_d by a Taylor step from lead_i with
// the first three derivatives, against the series evaluated in double at
// each lead, each term faded alike. Speeds from 0 to past the fade's end
// (the fundamental at 0 .. 8.5 times the loop's bandwidth), both
// directions; the drive's leads (T, 1.5 T, 20 kHz) with the default
// bandwidth (bw T = 0.08) and the largest (0.3, MC_PARAMS_BW_DT_MAX); the
// order-84 map, one of the same order with all six multiples it keeps, and
// the GM4108's order, 264. Tolerance per point (series_ref): the Taylor
// remainder, tau |w| sum g j A p^3 / 6 with p = j |w| (lead_d - lead_i),
// plus float's phase error (phase_error) on the current and on the
// derivative term, plus 1e-6 A for float's sums. The derivative taken at
// lead_i instead misses by more than ten times that tolerance: the test
// sees the Taylor step.
TEST(DriveCog, SeriesFeedForwardOnePassMatchesBothLeadsInDouble)
{
    struct Map {
        const char *name;
        uint32_t order;
        std::vector<double> amp;
    };
    const std::vector<Map> maps = {
        {"order 84, six multiples", 84u, {0.2, 0.08, 0.05, 0.03, 0.02, 0.01}},
        {"order 264 (GM4108)", 264u, {0.3}}};
    std::vector<mc_cog_series_t> sers;
    for (const Map &mp : maps) {
        mc_cog_map_t m{};
        mc_cog_series_t ser{};
        ASSERT_NO_FATAL_FAILURE(built_series(mp.order, mp.amp, &m, &ser)) << mp.name;
        sers.push_back(ser);
    }
    {
        mc_cog_map_t m{};
        mc_cog_series_t ser{};
        ASSERT_NO_FATAL_FAILURE(order84(&m, &ser));
        sers.push_back(ser);
    }
    const double t = 5.0e-5;
    for (const double bw_t : {0.08, 0.3}) {
        const mc_cog_loop_t lp = {static_cast<float>(t), static_cast<float>(1.5 * t),
                                  static_cast<float>(t / bw_t)};
        for (size_t k = 0; k < sers.size(); ++k) {
            const SweepResult res = sweep(sers[k], lp);
            const char *name = (k < maps.size()) ? maps[k].name : "order 84 (order84())";
            EXPECT_LE(res.worst_i, 1.0) << name << " bw T " << bw_t;
            EXPECT_LE(res.worst_r, 1.0)
                << name << " bw T " << bw_t << " at x1 " << res.x_of_worst_r;
            EXPECT_GT(res.at_i_miss, 10.0) << name << " bw T " << bw_t;
            std::printf("[ series one pass ] %s, bw T %g: error/tolerance %.3f (at x1 %g), "
                        "current %.3f; error %.2e of the largest reference; derivative at "
                        "lead_i: %.0f tolerances\n",
                        name, bw_t, res.worst_r, res.x_of_worst_r, res.worst_i, res.err_r_rel,
                        res.at_i_miss);
        }
    }
}

// A non-finite rate (or angle) gives 0, the reference and the current both,
// whatever the loop's leads (a lead of 0 makes the angle NaN, not infinite).
TEST(DriveCog, SeriesFeedForwardOfANonFiniteRateIsZero)
{
    mc_cog_map_t m{};
    mc_cog_series_t ser{};
    ASSERT_NO_FATAL_FAILURE(order84(&m, &ser));
    const mc_cog_loop_t leads[] = {{5.0e-5f, 7.5e-5f, 6.25e-4f}, {0.0f, 0.0f, 6.25e-4f}};
    for (const mc_cog_loop_t &lp : leads) {
        for (const float w : {NAN, INFINITY, -INFINITY}) {
            for (const float th : {0.0f, 1.3f, 6.2f}) {
                float i_a = 1.0f;
                EXPECT_EQ(mc_cog_series_ff_adv_a(&ser, th, w, &lp, &i_a), 0.0f) << w << " " << th;
                EXPECT_EQ(i_a, 0.0f) << w << " " << th;
            }
        }
        float i_a = 1.0f;
        EXPECT_EQ(mc_cog_series_ff_adv_a(&ser, INFINITY, 10.0f, &lp, &i_a), 0.0f);
        EXPECT_EQ(i_a, 0.0f);
    }
    // the same map at a finite rate is not 0 there (the check above is not
    // a map that gives 0 everywhere): 0.2 sin(84 1.3 + ...) at 10 rad/s
    float i_a = 0.0f;
    const float r = mc_cog_series_ff_adv_a(&ser, 1.3f, 10.0f, &leads[0], &i_a);
    EXPECT_GT(std::fabs(i_a), 0.01f);
    EXPECT_GT(std::fabs(r), 0.01f);
}

// The fade with frequency (MC_COG_FADE_START, MC_COG_FADE_END): the
// fundamental at 6 times the loop's bandwidth (x1 = |w| tau order) weighs
// half, at 9 times nothing, current and reference alike; below 4 times
// all of it (the test above, 2 times). Tolerances as above.
TEST(DriveCog, FeedForwardFadesAboveFourTimesTheLoopsBandwidth)
{
    mc_cog_map_t m{};
    mc_cog_series_t ser{};
    ASSERT_NO_FATAL_FAILURE(order84(&m, &ser));
    const mc_cog_loop_t lp = {0.0f, 0.0f, 4.0e-4f};
    for (const double x1 : {6.0, 9.0}) {
        const double w = x1 / (lp.tau_s * 84.0);
        const double g = (x1 < 8.0) ? (8.0 - x1) / 4.0 : 0.0;
        for (uint32_t j = 0; j < 13u; ++j) {
            const double th = 0.02 + 2.0 * kPi * j / 13.0;
            const double want_i = g * 0.2 * std::sin(84.0 * th);
            const double want = want_i + g * lp.tau_s * w * 0.2 * 84.0 * std::cos(84.0 * th);
            float i_a = 1.0f;
            const float r = mc_cog_series_ff_adv_a(&ser, static_cast<float>(th),
                                                   static_cast<float>(w), &lp, &i_a);
            EXPECT_NEAR(i_a, want_i, 2e-4) << x1 << " " << j;
            EXPECT_NEAR(r, want, 2e-3) << x1 << " " << j;
        }
    }
}

// The bins path's fade order (mc_cog_map_order_rms): a map of one order k
// (every order kept: the bins path) reads N sin(pi k / N) / pi, what the
// bins' half-bin slope makes of a sinusoid's derivative. Tolerance 1e-3
// relative: the entries' q15 rounding (half an LSB against entries scaled
// to 32767) and float sums over 1024 bins move it by under 1e-4.
TEST(DriveCog, RmsOrderOfAOneOrderMapIsItsBinSlopesOrder)
{
    for (const uint32_t k : {1u, 84u, 264u, 500u}) {
        const mc_cog_map_t m = built(sinusoid(0.2, k, 0.4, 0.0));
        const double want = kN * std::sin(kPi * k / kN) / kPi;
        EXPECT_NEAR(mc_cog_map_order_rms(&m), want, 1e-3 * want) << k;
    }
    // two orders: the RMS of their bin orders weighed by their squares
    std::vector<float> v = sinusoid(0.3, 84u, 0.0, 0.0);
    const std::vector<float> v2 = sinusoid(0.1, 168u, 1.0, 0.0);
    for (uint32_t i = 0; i < kN; ++i) {
        v[i] += v2[i];
    }
    const mc_cog_map_t m2 = built(v);
    const double o1 = kN * std::sin(kPi * 84.0 / kN) / kPi;
    const double o2 = kN * std::sin(kPi * 168.0 / kN) / kPi;
    const double want2 = std::sqrt((0.09 * o1 * o1 + 0.01 * o2 * o2) / 0.1);
    EXPECT_NEAR(mc_cog_map_order_rms(&m2), want2, 1e-3 * want2);
    mc_cog_map_t zero{};
    EXPECT_EQ(mc_cog_map_order_rms(&zero), 0.0f);
}

// The fade's gain at its corners and for a non-finite frequency (exact:
// the arithmetic is on small binary fractions).
TEST(DriveCog, FadeGainIsOneThenLinearThenZero)
{
    EXPECT_EQ(mc_cog_fade_gain(0.0f), 1.0f);
    EXPECT_EQ(mc_cog_fade_gain(MC_COG_FADE_START), 1.0f);
    EXPECT_EQ(mc_cog_fade_gain(6.0f), 0.5f);
    EXPECT_EQ(mc_cog_fade_gain(MC_COG_FADE_END), 0.0f);
    EXPECT_EQ(mc_cog_fade_gain(1e9f), 0.0f);
    EXPECT_EQ(mc_cog_fade_gain(NAN), 0.0f);
    EXPECT_EQ(mc_cog_fade_gain(INFINITY), 0.0f);
}

namespace
{
// Uniform noise in [-a, a], deterministic (a 64-bit LCG's top bits).
std::vector<float> noise(double a, uint64_t seed)
{
    std::vector<float> v(kN);
    for (uint32_t i = 0; i < kN; ++i) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        v[i] = static_cast<float>(
            a * (2.0 * static_cast<double>(seed >> 11) / 9007199254740992.0 - 1.0));
    }
    return v;
}
} // namespace

// The slots unknown (cog_slots 0): the order found in the currents is the
// slotted motor's lcm(Q, 2 p) when its line stands out of the noise: the
// SK3's 84 (12N14P) and the GM4108's 264 (24N22P) under noise of half the
// cogging's amplitude per bin (its power per order is 1/1000 of the line's:
// far above MC_COG_FIND_SNR); pure noise, or a line at an order no
// three-phase stator gives (85 for 7 pole pairs), keeps every order (0).
TEST(DriveCog, FindOrderPicksTheSlottedMotorsLineOrNone)
{
    struct Case {
        uint32_t k, p, want;
    };
    for (const Case c : {Case{84u, 7u, 84u}, Case{264u, 11u, 264u}, Case{85u, 7u, 0u}}) {
        std::vector<float> v = sinusoid(0.2, c.k, 0.7, 0.05);
        const std::vector<float> e = noise(0.1, c.k);
        for (uint32_t i = 0; i < kN; ++i) {
            v[i] += e[i];
        }
        EXPECT_EQ(mc_cog_find_order(v.data(), kN, c.p), c.want) << c.k;
    }
    for (uint64_t seed = 1u; seed <= 20u; ++seed) {
        const std::vector<float> e = noise(0.3, seed);
        EXPECT_EQ(mc_cog_find_order(e.data(), kN, 7u), 0u) << seed;
    }
    // bad input: refused as 0, nothing read past n
    const std::vector<float> v = sinusoid(0.2, 84u, 0.0, 0.0);
    EXPECT_EQ(mc_cog_find_order(nullptr, kN, 7u), 0u);
    EXPECT_EQ(mc_cog_find_order(v.data(), kN - 1u, 7u), 0u);
    EXPECT_EQ(mc_cog_find_order(v.data(), kN, 0u), 0u);
    std::vector<float> bad = v;
    bad[17] = NAN;
    EXPECT_EQ(mc_cog_find_order(bad.data(), kN, 7u), 0u);
    const std::vector<float> flat(kN, 0.3f);
    EXPECT_EQ(mc_cog_find_order(flat.data(), kN, 7u), 0u);
}
