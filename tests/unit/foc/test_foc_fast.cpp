// The FOC's fast path (firmware/kernels/foc/mc_foc.c: one screening for
// non-finite values, nothing committed until the step is good, one modulator
// solution) must give exactly what the checked definition of the step gives.
// The reference below is that definition written with the public building
// blocks: the transforms, mc_sincos_f32, mc_pi_f32_step_lim (the checked PI),
// mc_svpwm_max_voltage_f32, mc_sqrt_f32, mc_svpwm_limit_f32, mc_pi_f32_track
// and mc_svpwm_f32, with the input checks and the PI roll-back of mc_foc.h.
// No tolerance anywhere: the fast path promises the same operations on the
// same values, so every output and every state word must match bit for bit
// (NaN compared as "NaN", since its payload is not promised).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>

#include "foc/mc_foc.h"
#include "math/mc_math.h"
#include "transforms/mc_svpwm.h"
#include "transforms/mc_transforms.h"

namespace
{

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

bool Finite(float x)
{
    return std::isfinite(x);
}

// The checked dq step (mc_foc.h): checks, PIs with the d-priority limit,
// both PIs rolled back when one refuses.
uint32_t RefDq(mc_foc_f32_t *st, float id_ref, float iq_ref, float id, float iq, float omega,
               float vbus, float *p_vd, float *p_vq)
{
    *p_vd = 0.0f;
    *p_vq = 0.0f;
    if (!Finite(id_ref) || !Finite(iq_ref) || !Finite(id) || !Finite(iq) || !Finite(omega) ||
        !Finite(vbus)) {
        return MC_FOC_ERR_NAN_INPUT;
    }
    if (!(vbus > 0.0f))
        return MC_FOC_ERR_VBUS;
    // mc_foc.h: v_max = v_max_per_vbus * vbus, v_max_per_vbus = ratio times
    // the modulator's largest voltage per volt (computed by init).
    EXPECT_EQ(st->v_max_per_vbus,
              st->v_limit_ratio * mc_svpwm_max_voltage_f32(1.0f, st->limit_mode));
    const float v_max = st->v_max_per_vbus * vbus;
    // mc_foc.h: the feed-forward gains are L and psi with decoupling, 0 without.
    EXPECT_EQ(st->ff_lq_h, st->decouple ? st->lq_h : 0.0f);
    EXPECT_EQ(st->ff_ld_h, st->decouple ? st->ld_h : 0.0f);
    EXPECT_EQ(st->ff_flux_wb, st->decouple ? st->flux_wb : 0.0f);
    // mc_foc.h: the decoupling's currents predicted as i + w (i_ref - i)
    const float id_ff = id + (st->pred_d * (id_ref - id));
    const float iq_ff = iq + (st->pred_q * (iq_ref - iq));
    const float ff_d = -(omega * (st->ff_lq_h * iq_ff));
    const float ff_q = omega * ((st->ff_ld_h * id_ff) + st->ff_flux_wb);
    const mc_pi_f32_t d_saved = st->pi_d;
    const mc_pi_f32_t q_saved = st->pi_q;
    st->pi_d.flags = MC_PI_ERR_NONE;
    st->pi_q.flags = MC_PI_ERR_NONE;
    float vd = 0.0f;
    float vq = 0.0f;
    const uint32_t err_d = mc_pi_f32_step_lim(&st->pi_d, id_ref - id, ff_d, -v_max, v_max, &vd);
    const float room = (v_max * v_max) - (vd * vd);
    const float vq_max = (room > 0.0f) ? mc_sqrt_f32(room) : 0.0f;
    const uint32_t err_q = mc_pi_f32_step_lim(&st->pi_q, iq_ref - iq, ff_q, -vq_max, vq_max, &vq);
    // A step's return value is the flags it raised (kernels/README.md).
    EXPECT_EQ(err_d, st->pi_d.flags);
    EXPECT_EQ(err_q, st->pi_q.flags);
    if ((st->pi_d.flags | st->pi_q.flags) != MC_PI_ERR_NONE) {
        st->pi_d = d_saved;
        st->pi_q = q_saved;
        return MC_FOC_ERR_PI;
    }
    *p_vd = vd;
    *p_vq = vq;
    return MC_FOC_ERR_NONE;
}

uint32_t RefStepDq(mc_foc_f32_t *st, float id_ref, float iq_ref, float id, float iq, float omega,
                   float vbus, float *p_vd, float *p_vq)
{
    const uint32_t err = RefDq(st, id_ref, iq_ref, id, iq, omega, vbus, p_vd, p_vq);
    st->flags |= err;
    return err;
}

// The checked whole step from alpha-beta currents (mc_foc.h).
uint32_t RefStepAb(mc_foc_f32_t *st, float al, float be, const mc_foc_f32_in_t &in,
                   mc_foc_f32_out_t *out)
{
    out->svpwm_flags = MC_SVPWM_FLAG_NONE;
    out->id_a = 0.0f;
    out->iq_a = 0.0f;
    uint32_t err = MC_FOC_ERR_NONE;
    float s = 0.0f;
    float c = 1.0f;
    float vd = 0.0f;
    float vq = 0.0f;
    if (!Finite(al) || !Finite(be) || !Finite(in.theta_e_rad)) {
        err = MC_FOC_ERR_NAN_INPUT;
    } else {
        mc_sincos_f32(in.theta_e_rad, &s, &c);
        float id = 0.0f;
        float iq = 0.0f;
        mc_park_f32(al, be, s, c, &id, &iq);
        out->id_a = id;
        out->iq_a = iq;
        // mc_foc.h: the voltage angle theta + adv_s omega; one that overflows
        // (inputs otherwise good) is a non-finite input, nothing committed
        const float th_v = in.theta_e_rad + (st->adv_s * in.omega_e_rad_s);
        const bool inputs_ok = Finite(in.id_ref_a) && Finite(in.iq_ref_a) && Finite(id) &&
                               Finite(iq) && Finite(in.omega_e_rad_s) && Finite(in.vbus_v) &&
                               (in.vbus_v > 0.0f);
        if (inputs_ok && (st->adv_s > 0.0f) && !Finite(th_v)) {
            err = MC_FOC_ERR_NAN_INPUT;
        } else {
            err =
                RefDq(st, in.id_ref_a, in.iq_ref_a, id, iq, in.omega_e_rad_s, in.vbus_v, &vd, &vq);
        }
        if (st->adv_s > 0.0f) {
            mc_sincos_f32(th_v, &s, &c);
        }
    }
    if (err != MC_FOC_ERR_NONE) {
        st->flags |= err;
        out->duty_a = out->duty_b = out->duty_c = 0.5f;
        out->vd_v = out->vq_v = out->v_alpha_v = out->v_beta_v = 0.0f;
        out->flags = st->flags;
        return err;
    }
    float va = 0.0f;
    float vb = 0.0f;
    mc_inv_park_f32(vd, vq, s, c, &va, &vb);
    float la = va;
    float lb = vb;
    out->svpwm_flags = mc_svpwm_limit_f32(&la, &lb, in.vbus_v, st->limit_mode);
    if ((out->svpwm_flags & MC_SVPWM_FLAG_LIMITED) != 0u) {
        va = la;
        vb = lb;
        mc_park_f32(va, vb, s, c, &vd, &vq);
        (void)mc_pi_f32_track(&st->pi_d, vd);
        (void)mc_pi_f32_track(&st->pi_q, vq);
    }
    out->svpwm_flags |=
        mc_svpwm_f32(va, vb, in.vbus_v, st->limit_mode, &out->duty_a, &out->duty_b, &out->duty_c);
    out->vd_v = vd;
    out->vq_v = vq;
    out->v_alpha_v = va;
    out->v_beta_v = vb;
    out->flags = st->flags;
    return MC_FOC_ERR_NONE;
}

// The checked whole step (mc_foc.h): Clarke, then the step from alpha-beta
// (a non-finite current read makes alpha or beta non-finite).
uint32_t RefStep(mc_foc_f32_t *st, const mc_foc_f32_in_t &in, mc_foc_f32_out_t *out)
{
    float al = 0.0f;
    float be = 0.0f;
    if (in.three_phase) {
        mc_clarke3_f32(in.ia_a, in.ib_a, in.ic_a, &al, &be);
    } else {
        mc_clarke_f32(in.ia_a, in.ib_a, &al, &be);
    }
    return RefStepAb(st, al, be, in, out);
}

uint32_t Bits(float x)
{
    if (x != x)
        return 0x7FC00000u; // NaN: payload not promised
    uint32_t b = 0u;
    std::memcpy(&b, &x, sizeof b);
    return b;
}

#define EXPECT_SAME(a, b, what, k) EXPECT_EQ(Bits(a), Bits(b)) << (what) << " at step " << (k)

void ExpectSamePi(const mc_pi_f32_t &a, const mc_pi_f32_t &b, long k)
{
    EXPECT_SAME(a.integ, b.integ, "integ", k);
    EXPECT_SAME(a.integ_prev, b.integ_prev, "integ_prev", k);
    EXPECT_SAME(a.out, b.out, "out", k);
    EXPECT_SAME(a.last_error, b.last_error, "last_error", k);
    EXPECT_SAME(a.last_ff, b.last_ff, "last_ff", k);
    EXPECT_EQ(a.flags, b.flags) << "PI flags at step " << k;
}

// Operating values with, now and then, an edge value (NaN, inf, huge,
// denormal, zero): the fast path must hand those steps to the checked code.
class Draw
{
  public:
    explicit Draw(uint32_t seed) : g_(seed)
    {
    }
    float operator()(float lo, float hi)
    {
        const uint32_t r = g_() % 100u;
        if (r < 3u) {
            static const float kEdges[] = {0.0f,   -0.0f, 1e-40f, 1e30f, -1e30f, 3e38f,
                                           -3e38f, kInf,  -kInf,  kNaN,  1e19f,  -1e-30f};
            return kEdges[g_() % (sizeof kEdges / sizeof kEdges[0])];
        }
        const float v = std::uniform_real_distribution<float>(lo, hi)(g_);
        return (r < 6u) ? v * 1e4f : v; // far out of range: limits and saturation
    }
    uint32_t u()
    {
        return g_();
    }

  private:
    std::mt19937 g_;
};

mc_foc_f32_cfg_t Cfg(int variant)
{
    mc_foc_f32_cfg_t c{};
    c.r_ohm = 0.675f;
    c.ld_h = 1.14e-3f;
    c.lq_h = 1.3e-3f;
    c.flux_wb = 0.11f;
    c.kp_d_v_per_a = 1.43f;
    c.ki_d_v_per_as = 848.0f;
    c.kp_q_v_per_a = 1.6f;
    c.ki_q_v_per_as = 900.0f;
    c.dt_s = 5e-5f;
    c.aw = MC_PI_AW_CLAMP;
    c.kaw_per_s = 0.0f;
    c.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
    c.v_limit_ratio = 0.95f;
    c.v_abs_max_v = 200.0f;
    c.decouple = true;
    switch (variant) {
    case 1: // hexagon, the whole voltage: the modulator cuts on the flat sides
        c.limit_mode = MC_SVPWM_LIMIT_HEXAGON;
        c.v_limit_ratio = 1.0f;
        break;
    case 2: // back-calculation, circle at its edge (rounding cuts)
        c.aw = MC_PI_AW_BACK_CALC;
        c.kaw_per_s = 5000.0f;
        c.v_limit_ratio = 1.0f;
        break;
    case 3: // no anti-windup, no decoupling, a static limit that acts
        c.aw = MC_PI_AW_NONE;
        c.decouple = false;
        c.v_abs_max_v = 20.0f;
        break;
    case 4: // high gains against a small static limit
        c.v_abs_max_v = 5.0f;
        c.kp_d_v_per_a = 50.0f;
        c.kp_q_v_per_a = 50.0f;
        break;
    default:
        break;
    }
    return c;
}

class FocFastVsChecked : public ::testing::TestWithParam<int>
{
};

TEST_P(FocFastVsChecked, WholeStepAndDqStepBitIdentical)
{
    const mc_foc_f32_cfg_t cfg = Cfg(GetParam());
    mc_foc_f32_t fast{};
    mc_foc_f32_t ref{};
    ASSERT_EQ(mc_foc_f32_init(&fast, &cfg), MC_FOC_ERR_NONE);
    ASSERT_EQ(mc_foc_f32_init(&ref, &cfg), MC_FOC_ERR_NONE);
    Draw draw(1234u + static_cast<uint32_t>(GetParam()));
    long fast_ok = 0;
    for (long k = 0; k < 60000; ++k) {
        // A sticky flag keeps the fast path off until reset (mc_foc.h): reset
        // both now and then, so that the fast path keeps running after the
        // edge values and the checked one also runs with flags set.
        if ((ref.flags != MC_FOC_ERR_NONE) && ((draw.u() & 1u) != 0u)) {
            mc_foc_f32_reset(&fast);
            mc_foc_f32_reset(&ref);
        }
        mc_foc_f32_in_t in{};
        in.ia_a = draw(-20.0f, 20.0f);
        in.ib_a = draw(-20.0f, 20.0f);
        in.ic_a = draw(-20.0f, 20.0f);
        in.three_phase = (draw.u() & 1u) != 0u;
        in.theta_e_rad = draw(-10.0f, 10.0f);
        in.omega_e_rad_s = draw(-3000.0f, 3000.0f);
        in.vbus_v = ((k % 8) == 0) ? draw(-5.0f, 5.0f) : draw(5.0f, 400.0f);
        in.id_ref_a = draw(-20.0f, 20.0f);
        in.iq_ref_a = draw(-20.0f, 20.0f);
        uint32_t rf = 0u;
        uint32_t rr = 0u;
        if ((k % 5) == 4) {
            float vdf = 0.0f, vqf = 0.0f, vdr = 0.0f, vqr = 0.0f;
            rf = mc_foc_f32_step_dq(&fast, in.id_ref_a, in.iq_ref_a, in.ia_a, in.ib_a,
                                    in.omega_e_rad_s, in.vbus_v, &vdf, &vqf);
            rr = RefStepDq(&ref, in.id_ref_a, in.iq_ref_a, in.ia_a, in.ib_a, in.omega_e_rad_s,
                           in.vbus_v, &vdr, &vqr);
            EXPECT_SAME(vdf, vdr, "dq vd", k);
            EXPECT_SAME(vqf, vqr, "dq vq", k);
        } else {
            mc_foc_f32_out_t of{};
            mc_foc_f32_out_t orf{};
            if ((k % 5) == 3) {
                // the alpha-beta entry point, on raw draws for alpha and beta
                rf = mc_foc_f32_step_ab(&fast, in.ia_a, in.ib_a, in.theta_e_rad, in.omega_e_rad_s,
                                        in.vbus_v, in.id_ref_a, in.iq_ref_a, &of);
                rr = RefStepAb(&ref, in.ia_a, in.ib_a, in, &orf);
            } else {
                rf = mc_foc_f32_step(&fast, &in, &of);
                rr = RefStep(&ref, in, &orf);
            }
            EXPECT_SAME(of.duty_a, orf.duty_a, "duty_a", k);
            EXPECT_SAME(of.duty_b, orf.duty_b, "duty_b", k);
            EXPECT_SAME(of.duty_c, orf.duty_c, "duty_c", k);
            EXPECT_SAME(of.id_a, orf.id_a, "id", k);
            EXPECT_SAME(of.iq_a, orf.iq_a, "iq", k);
            EXPECT_SAME(of.vd_v, orf.vd_v, "vd", k);
            EXPECT_SAME(of.vq_v, orf.vq_v, "vq", k);
            EXPECT_SAME(of.v_alpha_v, orf.v_alpha_v, "v_alpha", k);
            EXPECT_SAME(of.v_beta_v, orf.v_beta_v, "v_beta", k);
            EXPECT_EQ(of.svpwm_flags, orf.svpwm_flags) << "svpwm flags at step " << k;
            EXPECT_EQ(of.flags, orf.flags) << "flags at step " << k;
        }
        EXPECT_EQ(rf, rr) << "return at step " << k;
        fast_ok += (rf == MC_FOC_ERR_NONE) ? 1 : 0;
        ExpectSamePi(fast.pi_d, ref.pi_d, k);
        ExpectSamePi(fast.pi_q, ref.pi_q, k);
        EXPECT_EQ(fast.flags, ref.flags) << "sticky flags at step " << k;
        if (::testing::Test::HasFailure()) {
            FAIL() << "first difference at step " << k;
        }
    }
    // Most steps are nominal (the edge values hit about a quarter of them):
    // the comparison covers the fast path, not only the hand-over.
    EXPECT_GT(fast_ok, 30000);
}

INSTANTIATE_TEST_SUITE_P(Configs, FocFastVsChecked, ::testing::Values(0, 1, 2, 3, 4));

// mc_svpwm_limit_duty_f32 is mc_svpwm_limit_f32 followed by mc_svpwm_f32 on
// the limited vector, bit for bit, for both limits, inside and outside them,
// and for bad input.
TEST(SvpwmLimitDuty, SameAsLimitThenModulator)
{
    Draw draw(99u);
    for (long k = 0; k < 200000; ++k) {
        const float scale = ((k & 1) != 0) ? 0.3f : 1.0f; // inside / outside the limit
        const float va = scale * draw(-300.0f, 300.0f);
        const float vb = scale * draw(-300.0f, 300.0f);
        const float vbus = draw(-10.0f, 400.0f);
        const mc_svpwm_limit_t lim =
            ((k % 3) == 0) ? MC_SVPWM_LIMIT_HEXAGON : MC_SVPWM_LIMIT_CIRCLE;
        float xa = va, xb = vb, ya = va, yb = vb;
        float d1[3] = {0.0f, 0.0f, 0.0f};
        float d2[3] = {0.0f, 0.0f, 0.0f};
        const uint32_t f1 = mc_svpwm_limit_duty_f32(&xa, &xb, vbus, lim, &d1[0], &d1[1], &d1[2]);
        uint32_t f2 = mc_svpwm_limit_f32(&ya, &yb, vbus, lim);
        f2 |= mc_svpwm_f32(ya, yb, vbus, lim, &d2[0], &d2[1], &d2[2]);
        ASSERT_EQ(f1, f2) << "flags at " << k;
        ASSERT_EQ(Bits(xa), Bits(ya)) << "limited alpha at " << k;
        ASSERT_EQ(Bits(xb), Bits(yb)) << "limited beta at " << k;
        for (int i = 0; i < 3; ++i)
            ASSERT_EQ(Bits(d1[i]), Bits(d2[i])) << "duty " << i << " at " << k;
    }
    float a = 1.0f;
    float d = 0.0f;
    EXPECT_EQ(mc_svpwm_limit_duty_f32(&a, nullptr, 24.0f, MC_SVPWM_LIMIT_CIRCLE, &d, &d, &d),
              MC_SVPWM_FLAG_BAD_INPUT);
    EXPECT_EQ(a, 1.0f); // nothing written with a NULL pointer
}

// The fast path's bus bound (mc_foc.h, vbus_fast_bits): the largest vbus,
// as bits, whose v_max = v_max_per_vbus * vbus stays within the PIs' static
// limit (so that the dynamic limit alone bounds the output there), capped
// at 2^59. Checked at the bound and one ulp above it, per variant: exact,
// no tolerance (it is a property of two float products).
TEST(FocFastBound, LargestBusWhoseVoltageLimitIsInsideTheStaticOne)
{
    for (int variant = 0; variant <= 4; ++variant) {
        const mc_foc_f32_cfg_t cfg = Cfg(variant);
        mc_foc_f32_t st{};
        ASSERT_EQ(mc_foc_f32_init(&st, &cfg), MC_FOC_ERR_NONE);
        const uint32_t b = st.vbus_fast_bound;
        ASSERT_EQ(st.vbus_fast_bits, b); // no sticky flag after init
        if (cfg.aw != MC_PI_AW_CLAMP) {
            // the fast path covers the clamping scheme only: none for the others
            EXPECT_EQ(b, 0u) << variant;
            continue;
        }
        ASSERT_GT(b, 0u);
        ASSERT_LE(b, 0x5D000000u);
        float at;
        float above;
        const uint32_t b1 = b + 1u;
        std::memcpy(&at, &b, sizeof at);
        std::memcpy(&above, &b1, sizeof above);
        EXPECT_LE(st.v_max_per_vbus * at, st.pi_d.out_max) << variant;
        EXPECT_EQ(st.pi_d.out_max, st.pi_q.out_max) << variant;
        if (b < 0x5D000000u) {
            EXPECT_GT(st.v_max_per_vbus * above, st.pi_d.out_max) << variant;
        }
        // 200 V static limit, 0.95 of the circle: v_max reaches 200 V at about
        // 364.6 V of bus
        if (variant == 0) {
            EXPECT_NEAR(at, 200.0f / (0.95f / std::sqrt(3.0f)), 1e-3f);
        }
    }
}

// A sticky flag turns the fast path off (its bus bound drops to 0) and
// reset turns it back on; the out flags report the sticky ones meanwhile.
// Exact: flags and bits, no arithmetic.
TEST(FocFastGate, StickyFlagKeepsTheCheckedPathUntilReset)
{
    const mc_foc_f32_cfg_t cfg = Cfg(0);
    mc_foc_f32_t st{};
    ASSERT_EQ(mc_foc_f32_init(&st, &cfg), MC_FOC_ERR_NONE);
    const uint32_t bound = st.vbus_fast_bound;
    mc_foc_f32_in_t in{};
    in.ia_a = 1.0f;
    in.ib_a = -0.5f;
    in.theta_e_rad = 0.3f;
    in.omega_e_rad_s = 100.0f;
    in.vbus_v = 24.0f;
    in.iq_ref_a = 2.0f;
    mc_foc_f32_out_t out{};
    ASSERT_EQ(mc_foc_f32_step(&st, &in, &out), MC_FOC_ERR_NONE);
    EXPECT_EQ(out.flags, MC_FOC_ERR_NONE);
    EXPECT_EQ(st.vbus_fast_bits, bound);

    mc_foc_f32_in_t bad = in;
    bad.omega_e_rad_s = kNaN;
    EXPECT_EQ(mc_foc_f32_step(&st, &bad, &out), MC_FOC_ERR_NAN_INPUT);
    EXPECT_EQ(st.vbus_fast_bits, 0u);

    // a good step afterwards runs (checked path) and still reports the flag
    EXPECT_EQ(mc_foc_f32_step(&st, &in, &out), MC_FOC_ERR_NONE);
    EXPECT_EQ(out.flags, MC_FOC_ERR_NAN_INPUT);
    EXPECT_EQ(st.vbus_fast_bits, 0u);

    mc_foc_f32_reset(&st);
    EXPECT_EQ(st.flags, MC_FOC_ERR_NONE);
    EXPECT_EQ(st.vbus_fast_bits, bound);
    EXPECT_EQ(mc_foc_f32_step(&st, &in, &out), MC_FOC_ERR_NONE);
    EXPECT_EQ(out.flags, MC_FOC_ERR_NONE);

    // the dq entry point raises the same way
    float vd = 0.0f;
    float vq = 0.0f;
    EXPECT_EQ(mc_foc_f32_step_dq(&st, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, -1.0f, &vd, &vq),
              MC_FOC_ERR_VBUS);
    EXPECT_EQ(st.vbus_fast_bits, 0u);
}

} // namespace
