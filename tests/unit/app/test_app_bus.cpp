// The DC-bus current and power limits (firmware/app/drive/mc_drive_bus.h):
// the estimate, the quadratic limits against closed forms, the correction
// closing on a motor whose R the drive has wrong, and the configuration's
// refusals (the drive's init, the parameter table).
#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "app_test_fixture.h"
#include "mc_params.h"
#include "mc_drive_bus.h"

namespace apptest
{
namespace
{

// 3/2 (vd id + vq iq) / vbus: 1.5 (2 (-1) + 10 5) / 24 = 3 A; no bus or a
// value that is not a number gives 0. Tolerance: one float rounding.
TEST(DriveBusEstimate, ClosedForm)
{
    EXPECT_NEAR(3.0f, mc_drive_bus_estimate_a(2.0f, 10.0f, -1.0f, 5.0f, 24.0f), 1e-6f);
    EXPECT_NEAR(-3.0f, mc_drive_bus_estimate_a(2.0f, 10.0f, 1.0f, -5.0f, 24.0f), 1e-6f);
    EXPECT_EQ(0.0f, mc_drive_bus_estimate_a(2.0f, 10.0f, -1.0f, 5.0f, 0.0f));
    EXPECT_EQ(0.0f, mc_drive_bus_estimate_a(kNaN, 10.0f, -1.0f, 5.0f, 24.0f));
}

float Poly(float a, float b, float c, float x)
{
    return (a * x * x) + (b * x) + c;
}

// Motoring: the range of iq with a iq^2 + b iq + c0 <= P is bounded by the
// two roots, where the power is P (1e-4 relative: float roots of a
// well-conditioned quadratic); none when even the vertex draws more; the
// linear model (R = 0) bounds one side only.
TEST(DriveBusLimit, MotoringRangeIsBetweenTheRoots)
{
    const float a = 0.15f;
    const float b = 1.5f;
    const float c0 = 0.3f;
    float lo = 0.0f;
    float hi = 0.0f;
    ASSERT_TRUE(mc_drive_bus_motor_range(a, b, c0, 6.0f, &lo, &hi));
    EXPECT_NEAR(6.0f, Poly(a, b, c0, lo), 6e-4f);
    EXPECT_NEAR(6.0f, Poly(a, b, c0, hi), 6e-4f);
    EXPECT_LT(lo, 0.0f);
    EXPECT_GT(hi, 0.0f);
    // vertex at -5: 0.15 * 25 - 7.5 + 0.3 = -3.45 W; a limit below it
    EXPECT_FALSE(mc_drive_bus_motor_range(a, b, c0, -4.0f, &lo, &hi));
    ASSERT_TRUE(mc_drive_bus_motor_range(0.0f, b, c0, 6.0f, &lo, &hi));
    EXPECT_NEAR((6.0f - 0.3f) / 1.5f, hi, 1e-6f);
    EXPECT_LT(lo, -1e30f);
}

// Regenerating: a reference in the band where the power is below -P moves
// to the band's edge nearer zero (power exactly -P, 1e-4 relative); one
// outside stays; one past the far edge (plugging, which the current limit
// would pull back into the band) also goes to the near edge.
TEST(DriveBusLimit, RegenerativeBandToItsNearEdge)
{
    const float a = 0.15f;
    const float b = -1.5f; // braking with iq > 0 at negative speed
    const float c0 = 0.0f;
    const float pr = 1.5f;
    const float near = (10.0f - std::sqrt(60.0f)) / 2.0f;
    const float x = mc_drive_bus_regen_clamp(a, b, c0, pr, 5.0f);
    EXPECT_NEAR(near, x, 1e-4f * near);
    EXPECT_NEAR(-pr, Poly(a, b, c0, x), 1e-4f * pr);
    EXPECT_EQ(0.5f, mc_drive_bus_regen_clamp(a, b, c0, pr, 0.5f));
    EXPECT_EQ(-2.0f, mc_drive_bus_regen_clamp(a, b, c0, pr, -2.0f)); // motoring side
    EXPECT_NEAR(near, mc_drive_bus_regen_clamp(a, b, c0, pr, 9.5f), 1e-4f * near);
    // no band: the vertex (-3.75 W) above -5 W
    EXPECT_EQ(5.0f, mc_drive_bus_regen_clamp(a, b, c0, 5.0f, 5.0f));
}

// A motor model for the closed loop below: steady-state dq voltages.
struct Motor {
    float r, ld, lq, psi, w;
    void Volts(float id, float iq, float *vd, float *vq) const
    {
        *vd = (r * id) - (w * lq * iq);
        *vq = (r * iq) + (w * ((ld * id) + psi));
    }
};

// The limiter in a loop with an ideal current loop (the next step measures
// the reference it gave) on a motor whose R is 30 % above the drive's: the
// estimate's correction takes up the difference, and after 20 filter time
// constants the true bus current is at the motoring limit within 0.5 %
// (the filter's residue e^-20 is nil; the rest is the one-step lag of the
// measured current behind the reference while the correction moves).
// Braking the same way to the regenerative limit. The power limit, lower
// than the current limit times the bus, is the one in force.
TEST(DriveBusLimit, CorrectionClosesOnAWrongResistance)
{
    mc_foc_f32_cfg_t foc = GoodCfg().foc;
    const Motor m{1.3f * foc.r_ohm, foc.ld_h, foc.lq_h, foc.flux_wb, 2000.0f};
    const float vbus = 24.0f;
    mc_drive_bus_cfg_t cfg{};
    cfg.i_bus_max_a = 1.0f;
    cfg.i_bus_regen_max_a = 0.5f;
    mc_drive_bus_t s;
    for (const float sign : {1.0f, -1.0f}) {
        const Motor mm{m.r, m.ld, m.lq, m.psi, sign * m.w};
        mc_drive_bus_init(&s, &foc);
        float id_meas = 0.0f;
        float iq_meas = 0.0f;
        const int n = static_cast<int>(20.0f * MC_DRIVE_BUS_CORR_TAU_LOOPS * foc.lq_h /
                                       foc.kp_q_v_per_a / foc.dt_s);
        for (int k = 0; k < n; ++k) {
            mc_drive_bus_in_t in{vbus,    mm.w,    true, static_cast<uint32_t>(k),
                                 id_meas, iq_meas, 0.0f, 0.0f};
            mm.Volts(id_meas, iq_meas, &in.vd_v, &in.vq_v);
            float id = 0.0f;
            float iq = 15.0f; // motoring at +w, braking at -w
            mc_drive_bus_limit(&s, &cfg, &foc, &in, &id, &iq);
            id_meas = id;
            iq_meas = iq;
        }
        float vd;
        float vq;
        mm.Volts(id_meas, iq_meas, &vd, &vq);
        const float i_true = mc_drive_bus_estimate_a(vd, vq, id_meas, iq_meas, vbus);
        const float want = (sign > 0.0f) ? cfg.i_bus_max_a : -cfg.i_bus_regen_max_a;
        EXPECT_NEAR(want, i_true, 0.005f * std::fabs(want)) << "sign " << sign;
        EXPECT_TRUE(s.limiting);
    }
    // the power limit below i_bus_max_a vbus is the one in force
    cfg.p_bus_max_w = 12.0f;
    float id = 0.0f;
    float iq = 1.0f;
    const mc_drive_bus_in_t in{vbus, 0.0f, true, 0u, 0.0f, 0.0f, 0.0f, 0.0f};
    mc_drive_bus_limit(&s, &cfg, &foc, &in, &id, &iq);
    EXPECT_NEAR(0.5f, s.i_mot_lim_a, 1e-6f);
}

// A discrete current loop as the drive runs it: this step samples i_k,
// the PI's voltage acts one period later (the computation delay), the
// winding integrates it over the period. The power of each period is
// 3/2 v i at the period's mean current.
struct DelayedLoop {
    float r, l, t, kp, ki;
    float i = 0.0f, v_act = 0.0f, v_last = 0.0f, i_last = 0.0f, integ = 0.0f;
    float Step(float q) // returns the power of the period [W]
    {
        const float i_k = i;
        const float e = q - i_k;
        const float v_new = (kp * e) + integ;
        integ += ki * t * e;
        const float i_next = i_k + (t / l) * (v_act - (r * i_k));
        const float p = 1.5f * v_act * 0.5f * (i_k + i_next);
        i_last = i_k;
        v_last = v_new;
        v_act = v_new;
        i = i_next;
        return p;
    }
};

// The current loop's transient (mc_drive_bus.c, limit_slew): a step of
// the q reference from rest to 200 A on paper 002's 40 kW motor
// (R 0.065 ohm, L 0.655 mH) at 8 kHz with a 640 rad/s current loop and a
// 5 kW motoring limit. With the references the steady-state range alone
// allows (the winding's 3/2 L i di/dt not in it) the supply power
// overshoots the limit by more than 20 % while the current rises; through
// mc_drive_bus_limit it stays within 2 % of it (the scenario's tolerance,
// issue 33 item 5: what the model leaves out is the PI's integral and the
// mean current's curvature within the period), and the current still
// reaches the 200 A asked within 400 periods (50 ms) (the bound slows the
// rise, it does not stall it: 5 kW / (3/2 R) allows 226 A at standstill,
// so the 200 A asked is reached).
TEST(DriveBusLimit, TransientOfAStepFromRestWithinTheLimit)
{
    mc_foc_f32_cfg_t foc = GoodCfg().foc;
    foc.r_ohm = 0.065f;
    foc.ld_h = 0.655e-3f;
    foc.lq_h = 0.655e-3f;
    foc.flux_wb = 0.146f;
    foc.dt_s = 1.0f / 8000.0f;
    foc.kp_q_v_per_a = foc.lq_h * 640.0f;
    const float ki = foc.r_ohm * 640.0f;
    const float vbus = 240.0f;
    const float p_m = 5000.0f;
    mc_drive_bus_cfg_t cfg{};
    cfg.p_bus_max_w = p_m;
    float peak[2] = {0.0f, 0.0f};
    float i_end[2] = {0.0f, 0.0f};
    for (int with = 0; with < 2; ++with) {
        DelayedLoop loop{foc.r_ohm, foc.lq_h, foc.dt_s, foc.kp_q_v_per_a, ki};
        mc_drive_bus_t s;
        mc_drive_bus_init(&s, &foc);
        for (uint32_t k = 0u; k < 400u; ++k) {
            float id = 0.0f;
            float iq = 200.0f;
            if (with == 1) {
                const mc_drive_bus_in_t in{vbus, 0.0f,        true, k,
                                           0.0f, loop.i_last, 0.0f, loop.v_last};
                mc_drive_bus_limit(&s, &cfg, &foc, &in, &id, &iq);
            } else {
                float lo = 0.0f;
                float hi = 0.0f;
                ASSERT_TRUE(mc_drive_bus_motor_range(1.5f * foc.r_ohm, 0.0f, 0.0f, p_m, &lo, &hi));
                iq = std::fmin(iq, hi);
            }
            peak[with] = std::fmax(peak[with], loop.Step(iq));
        }
        i_end[with] = loop.i;
    }
    EXPECT_GT(peak[0], 1.2f * p_m) << "the steady-state range alone";
    EXPECT_LE(peak[1], 1.02f * p_m);
    EXPECT_NEAR(200.0f, i_end[1], 2.0f); // 1 %: the PI's residual after 400 periods
}

// Bad limits are refused by name and change nothing: the drive's init
// (negative, NaN, infinite: MC_DRIVE_CFG_ERR_BUS_POWER), and the parameter
// table's range check for each of ids 150-153 (negative, NaN, above max).
TEST_F(AppDrive, BusLimitsRefused)
{
    InitDrive();
    const mc_drive_t before = d;
    const float bad[3] = {-1.0f, kNaN, kInf};
    for (const float v : bad) {
        for (int k = 0; k < 4; ++k) {
            mc_drive_cfg_t c = cfg;
            float *f[4] = {&c.bus.i_bus_max_a, &c.bus.i_bus_regen_max_a, &c.bus.p_bus_max_w,
                           &c.bus.p_bus_regen_max_w};
            *f[k] = v;
            EXPECT_EQ(MC_DRIVE_CFG_ERR_BUS_POWER, mc_drive_init(&d, &c, hal)) << k << " " << v;
            EXPECT_EQ(MC_DRIVE_CFG_ERR_BUS_POWER, mc_drive_check_cfg(&c));
        }
    }
    EXPECT_EQ(0, std::memcmp(&before, &d, sizeof d));
    for (const char *name :
         {"i_bus_max_a", "i_bus_regen_max_a", "p_bus_max_w", "p_bus_regen_max_w"}) {
        const int32_t i = mc_param_find_name(name);
        ASSERT_GE(i, 0) << name;
        const mc_param_info_t &info = mc_param_table[i];
        EXPECT_GE(info.id, 150u);
        EXPECT_LE(info.id, 159u);
        mc_param_value_t raw;
        for (const float v : {-1.0f, kNaN, 2.0f * info.max.f}) {
            raw.f = v;
            EXPECT_EQ(MC_PARAM_ERR_RANGE, mc_param_check_value(&info, raw.u)) << name << " " << v;
        }
        raw.f = 0.0f; // off
        EXPECT_EQ(MC_PARAM_OK, mc_param_check_value(&info, raw.u));
        mc_params_t p = mc_params_default;
        raw.f = -1.0f;
        mc_param_set_raw(&p, &info, raw.u);
        EXPECT_NE(0u, mc_params_validate(&p) & MC_PARAMS_ERR_RANGE) << name;
    }
}

// The drive runs the limiter only while a limit is set (mc_drive_t.bus_on,
// so the default configuration pays nothing in the fast interrupt): a
// limit set at run time (mc_drive_set_runtime_limits, the path of a
// parameter APPLY) holds the q reference from the next step, and clearing
// it releases the reference and shows no limit in force. With no current
// measured the bus power is 1.5 R (id^2 + iq^2) (the fake's rotor stands),
// so i_bus_max_a 0.01 A at 24 V (0.24 W) with id = 1 A allows |iq| <=
// sqrt((0.24 - 0.15) / 0.15) = 0.775 A of the 5 A asked. Tolerances: float
// rounding of the closed form.
TEST_F(AppDrive, BusLimitSetAndClearedAtRunTime)
{
    InitRunning();
    EXPECT_FALSE(d.bus_on);
    EXPECT_NEAR(5.0f, d.tm.iq_ref_a, 1e-6f);
    mc_drive_cfg_t c = cfg;
    c.bus.i_bus_max_a = 0.01f;
    mc_drive_set_runtime_limits(&d, &c);
    EXPECT_TRUE(d.bus_on);
    GoodSample();
    (void)mc_drive_fast_step(&d);
    ASSERT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    EXPECT_NEAR(std::sqrt(0.09f / 0.15f), d.tm.iq_ref_a, 1e-4f);
    EXPECT_TRUE(d.bus.limiting);
    EXPECT_NEAR(0.01f, d.bus.i_mot_lim_a, 1e-7f);
    mc_drive_set_runtime_limits(&d, &cfg);
    EXPECT_FALSE(d.bus_on);
    EXPECT_FALSE(d.bus.limiting);
    EXPECT_EQ(0.0f, d.bus.i_mot_lim_a);
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_NEAR(5.0f, d.tm.iq_ref_a, 1e-6f);
}

} // namespace
} // namespace apptest
