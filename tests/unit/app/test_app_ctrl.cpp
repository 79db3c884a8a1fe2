// The control-law plug-in interface of the drive (MC_DRIVE_MODE_CTRL):
// attach rules, what the law is given and where its duties go, and how its
// errors are handled. The law here is a recording stub defined in the test.
#include <cerrno>
#include <cmath>

#include <gtest/gtest.h>

#include "app_test_fixture.h"
#include "math/mc_math.h"
#include "transforms/mc_transforms.h"

#include <cmath>

namespace apptest
{
namespace
{

struct StubLaw {
    uint32_t resets = 0, fasts = 0, slows = 0, r_sets = 0;
    uint32_t reset_ret = 0, fast_ret = 0, slow_ret = 0, r_ret = 0;
    float r_scale = 0.0f;
    mc_drive_meas_t last{};
    mc_drive_out_t out = Out();
    static mc_drive_out_t Out()
    {
        mc_drive_out_t o{};
        o.duty_a = 0.2f;
        o.duty_b = 0.5f;
        o.duty_c = 0.8f;
        o.duty2_a = 0.25f;
        o.duty2_b = -0.75f;
        return o;
    }
};

uint32_t stub_reset(void *ctx)
{
    auto *s = static_cast<StubLaw *>(ctx);
    s->resets++;
    return s->reset_ret;
}
uint32_t stub_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    auto *s = static_cast<StubLaw *>(ctx);
    s->fasts++;
    s->last = *m;
    *out = s->out;
    return s->fast_ret;
}
uint32_t stub_slow(void *ctx)
{
    auto *s = static_cast<StubLaw *>(ctx);
    s->slows++;
    return s->slow_ret;
}

uint32_t stub_set_r_scale(void *ctx, float r_scale)
{
    auto *s = static_cast<StubLaw *>(ctx);
    s->r_sets++;
    s->r_scale = r_scale;
    return s->r_ret;
}

class AppDriveCtrl : public AppDrive
{
  protected:
    mc_drive_ctrl_t Law(uint32_t outputs, bool needs_encoder = true)
    {
        return mc_drive_ctrl_t{outputs, needs_encoder, stub_reset, stub_fast, stub_slow, &law,
                               nullptr, false,         false,      nullptr,   false};
    }
    StubLaw law;
};

TEST_F(AppDriveCtrl, AttachRules)
{
    InitDrive();
    mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    c.fast = nullptr;
    EXPECT_EQ(-EINVAL, mc_drive_attach_ctrl(&d, &c));
    c = Law(5u);
    EXPECT_EQ(-EINVAL, mc_drive_attach_ctrl(&d, &c));
    EXPECT_EQ(nullptr, d.ctrl);
    // CTRL without a law attached.
    EXPECT_EQ(-ENODEV, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    // A board without the law's bridge or its encoder.
    mc_hal_t h = fake.board;
    h.pwm2 = nullptr;
    h.encoder = nullptr;
    ASSERT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &cfg, &h));
    c = Law(MC_DRIVE_OUT_PWM2);
    EXPECT_EQ(-ENODEV, mc_drive_attach_ctrl(&d, &c));
    c = Law(MC_DRIVE_OUT_PWM3, true);
    EXPECT_EQ(-ENODEV, mc_drive_attach_ctrl(&d, &c));
    c = Law(MC_DRIVE_OUT_PWM3, false); // a sensorless law needs no encoder
    EXPECT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    // CURRENT mode needs the encoder.
    EXPECT_EQ(-ENODEV, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
}

TEST_F(AppDriveCtrl, NotWhileRunning)
{
    InitDrive();
    const mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    EXPECT_EQ(-EBUSY, mc_drive_attach_ctrl(&d, nullptr));
    EXPECT_EQ(&c, d.ctrl);
    EXPECT_EQ(-EBUSY, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
}

TEST_F(AppDriveCtrl, RunsTheLawAndWritesItsThreePhaseDuties)
{
    InitDrive();
    const mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    EXPECT_EQ(1u, law.resets);
    EXPECT_TRUE(fake.pwm3.enabled);
    ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 1024u, MC_HAL_ENCODER_FLAG_VALID));
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 1.5f, -0.5f, 0.0f, kVbus, kMask3));
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_MODE_CTRL, d.mode);
    EXPECT_EQ(1u, law.fasts);
    // Measurements passed through unchanged (copies: exact).
    EXPECT_EQ(1.5f, law.last.ia_a);
    EXPECT_EQ(-0.5f, law.last.ib_a);
    EXPECT_EQ(kVbus, law.last.vbus_v);
    EXPECT_TRUE(law.last.have_encoder);
    EXPECT_EQ(1024u, law.last.enc_count);
    EXPECT_EQ(1024u, law.last.enc_raw_count);
    EXPECT_EQ(d.tm.theta_e_rad, law.last.theta_e_rad);
    EXPECT_EQ(kDt, law.last.dt_s);
    // Its duties reached the 3-phase bridge.
    EXPECT_EQ(0.2f, fake.pwm3.duty_a);
    EXPECT_EQ(0.5f, fake.pwm3.duty_b);
    EXPECT_EQ(0.8f, fake.pwm3.duty_c);
    // The slow loop reaches the law too.
    for (uint32_t k = 0; k < cfg.slow_loop_div; ++k) {
        GoodSample();
        if (mc_drive_fast_step(&d)) {
            mc_drive_slow_step(&d);
        }
    }
    EXPECT_EQ(1u, law.slows);
}

// A reversed encoder (encoder_reversed: it counts down as the rotor turns
// positive): the law gets the count in the rotor's positive direction, the
// one theta_m_rad is made of, so a law that counts turns (position, CSMC)
// moves the way the drive's angle does; the encoder's own count stays there
// for commissioning, which identifies the direction from it. Exact: integer
// counts, and theta_m_rad is count * (2 pi / cpr) in the drive.
TEST_F(AppDriveCtrl, ReversedEncoderHandsTheLawThePositiveDirectionCount)
{
    cfg.encoder_reversed = true;
    InitDrive();
    const mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 1024u, MC_HAL_ENCODER_FLAG_VALID));
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 1.5f, -0.5f, 0.0f, kVbus, kMask3));
    (void)mc_drive_fast_step(&d);
    ASSERT_EQ(1u, law.fasts);
    const uint32_t cpr = law.last.enc_cpr;
    ASSERT_GT(cpr, 1024u);
    EXPECT_EQ(1024u, law.last.enc_raw_count);
    EXPECT_EQ(cpr - 1024u, law.last.enc_count);
    EXPECT_EQ((float)law.last.enc_count * (MC_TWO_PI_F32 / (float)cpr), law.last.theta_m_rad);
}

TEST_F(AppDriveCtrl, StepperLawDrivesTheDualHBridgeWithoutAThirdPhase)
{
    InitDrive();
    const mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM2);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    EXPECT_TRUE(fake.pwm2.enabled);
    EXPECT_FALSE(fake.pwm3.enabled);
    // Two winding currents of 0.6 trip each: a derived third phase would be
    // 1.2 trip and trip; a stepper has no third phase.
    const uint32_t mask2 = MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_VBUS;
    ASSERT_EQ(0,
              mc_hal_fake_adc_set_sample(&fake, 0.6f * kITrip, 0.6f * kITrip, 0.0f, kVbus, mask2));
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    EXPECT_EQ(0.0f, law.last.ic_a);
    EXPECT_EQ(0.25f, fake.pwm2.duty_a);
    EXPECT_EQ(-0.75f, fake.pwm2.duty_b);
}

TEST_F(AppDriveCtrl, LawErrorsAreControlFaults)
{
    InitDrive();
    const mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    law.reset_ret = 3u;
    EXPECT_EQ(-EINVAL, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    EXPECT_FALSE(fake.pwm3.enabled);
    law.reset_ret = 0u;
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    law.fast_ret = 0x40u;
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_EQ(MC_DRIVE_FAULT_CONTROL, d.faults);
    EXPECT_EQ(0x40u, d.tm.ctrl_err);
    EXPECT_FALSE(fake.pwm3.enabled);
}

TEST_F(AppDriveCtrl, SlowErrorIsAControlFault)
{
    InitDrive();
    const mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    law.slow_ret = 9u;
    mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_CONTROL, d.faults);
    EXPECT_FALSE(fake.pwm3.enabled);
}

// winding_r_follow (issue 33 item 2): with the winding model on, the slow
// step hands the running law the estimate's scale of R and sets the
// current loop's ki to match; off (or the model off), neither is touched;
// a law refusing the scale is a control fault. The estimate starts from
// the motor thermistor at 120 C: R(120) / R(25) of copper, exact to float
// rounding (1e-5 relative: the estimate moves by a few mK over one slow
// step at zero current).
TEST_F(AppDriveCtrl, TheLawAndTheCurrentLoopGetTheWindingsR)
{
    cfg.thermal.model_enable = true;
    cfg.thermal.r_follow = true;
    cfg.thermal.r_ohm = 0.1f;
    cfg.thermal.i_rated_a = 10.0f;
    cfg.thermal.rise_k = 80.0f;
    cfg.thermal.share = 0.3f;
    cfg.thermal.tau_w_s = 30.0f;
    cfg.thermal.tau_h_s = 900.0f;
    cfg.thermal.ambient_c = 25.0f;
    InitDrive();
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 30.0f, 120.0f, MC_HAL_ADC_TEMP_VALID_ALL));
    mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    c.set_r_scale = stub_set_r_scale;
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    mc_drive_slow_step(&d); // IDLE: the estimate starts, no law runs
    EXPECT_EQ(0u, law.r_sets);
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    mc_drive_slow_step(&d);
    const float a = MC_DRIVE_THERMAL_ALPHA_CU_1_K;
    const float want = (1.0f + a * (120.0f - 20.0f)) / (1.0f + a * (25.0f - 20.0f));
    EXPECT_EQ(1u, law.r_sets);
    EXPECT_NEAR(want, law.r_scale, 1e-5f * want);
    EXPECT_NEAR(want * cfg.foc.ki_q_v_per_as, d.foc.pi_q.ki_per_s, 1e-5f * want * 100.0f);
    EXPECT_EQ(cfg.foc.kp_q_v_per_a, d.foc.pi_q.kp);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    law.r_ret = 7u; // the law refuses: a control fault, the law's slow not run
    const uint32_t slows = law.slows;
    mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_CONTROL, d.faults);
    EXPECT_EQ(slows, law.slows);
}

TEST_F(AppDriveCtrl, WithoutRFollowTheLawsRStays)
{
    cfg.thermal.model_enable = true;
    cfg.thermal.r_follow = false;
    cfg.thermal.r_ohm = 0.1f;
    cfg.thermal.i_rated_a = 10.0f;
    cfg.thermal.rise_k = 80.0f;
    cfg.thermal.share = 0.3f;
    cfg.thermal.tau_w_s = 30.0f;
    cfg.thermal.tau_h_s = 900.0f;
    cfg.thermal.ambient_c = 25.0f;
    InitDrive();
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 30.0f, 120.0f, MC_HAL_ADC_TEMP_VALID_ALL));
    mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    c.set_r_scale = stub_set_r_scale;
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    mc_drive_slow_step(&d);
    mc_drive_slow_step(&d);
    EXPECT_EQ(0u, law.r_sets);
    EXPECT_EQ(cfg.foc.ki_q_v_per_as, d.foc.pi_q.ki_per_s);
    EXPECT_GT(d.thermal.t_w_c, 119.0f); // the model runs all the same
}

TEST_F(AppDriveCtrl, InvalidLawDutiesArePwmFaults)
{
    // The HAL refuses a NaN duty; the drive treats the refusal as a fault.
    InitDrive();
    const mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    law.out.duty_b = std::nanf("");
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_PWM, d.faults);
    EXPECT_FALSE(fake.pwm3.enabled);
}

// A law that gives current references (MC_DRIVE_OUT_CURRENT): the drive's
// current loop runs them, the same loop as CURRENT mode. Against CURRENT
// mode with the same references at the same angle: the same duties, bit for
// bit (the same code on the same inputs).
TEST_F(AppDriveCtrl, CurrentLawRunsTheDrivesOwnLoop)
{
    // the reference: CURRENT mode, 2 A d, 5 A q, two steps
    InitDrive();
    ASSERT_EQ(0, mc_drive_set_current_ref(&d, 2.0f, 5.0f));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 1.0f, -0.25f, 0.0f, kVbus, kMask3));
    (void)mc_drive_fast_step(&d);
    const mc_foc_f32_out_t want = d.tm.foc;
    const float want_duty[3] = {fake.pwm3.duty_a, fake.pwm3.duty_b, fake.pwm3.duty_c};
    // the law at the encoder's angle and speed, the same references
    InitDrive();
    mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_CURRENT);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    law.out = mc_drive_out_t{};
    law.out.id_ref_a = 2.0f;
    law.out.iq_ref_a = 5.0f;
    law.out.rotor_frame = true;
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 1.0f, -0.25f, 0.0f, kVbus, kMask3));
    // the law sees the encoder's angle (count 0: the offset); the stub
    // answers with the angle of the previous meas, so set it to the same
    law.out.theta_e_rad = kOffset;
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_MODE_CTRL, d.mode);
    EXPECT_EQ(2.0f, d.tm.id_ref_a);
    EXPECT_EQ(5.0f, d.tm.iq_ref_a);
    EXPECT_EQ(want.vd_v, d.tm.foc.vd_v);
    EXPECT_EQ(want.vq_v, d.tm.foc.vq_v);
    EXPECT_EQ(want_duty[0], fake.pwm3.duty_a);
    EXPECT_EQ(want_duty[1], fake.pwm3.duty_b);
    EXPECT_EQ(want_duty[2], fake.pwm3.duty_c);
    // the law is told the limit in force and what the loop commanded
    EXPECT_EQ(kIMax, law.last.i_max_a);
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(5.0f, law.last.iq_applied_a);
    EXPECT_EQ(want.v_alpha_v, law.last.v_alpha_prev_v);
    EXPECT_EQ(want.v_beta_v, law.last.v_beta_prev_v);
}

// A reference above the current limit is saturated there, never dropped;
// a limit lowered at run time saturates it from the next step, and the law
// is told the limit in force (mc_drive_meas_t.i_max_a) and what was applied.
TEST_F(AppDriveCtrl, CurrentLawIsSaturatedAtTheLimitInForce)
{
    InitDrive();
    mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_CURRENT);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    law.out = mc_drive_out_t{};
    law.out.id_ref_a = -30.0f;
    law.out.iq_ref_a = 25.0f;
    law.out.rotor_frame = true;
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    EXPECT_EQ(-kIMax, d.tm.id_ref_a);
    EXPECT_EQ(kIMax, d.tm.iq_ref_a);
    mc_drive_cfg_t lower = d.cfg;
    lower.i_max_a = 8.0f;
    mc_drive_set_runtime_limits(&d, &lower);
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(8.0f, law.last.i_max_a);
    EXPECT_EQ(kIMax, law.last.iq_applied_a); // the last step's, before the change
    EXPECT_EQ(8.0f, d.tm.iq_ref_a);
    EXPECT_EQ(-8.0f, d.tm.id_ref_a);
    EXPECT_EQ(MC_DRIVE_MODE_CTRL, d.mode);
}

// A speed law (uses_speed_ref): the drive slews the target at
// speed_accel_rad_s2 each fast step, hands the reference and its
// acceleration to the law, lands on the target exactly; a controlled stop
// ramps it to 0 at stop_decel_rad_s2 with the law still running, then opens
// the bridge. The reference against float sums of the steps (1e-6); it
// ends on the target exactly.
TEST_F(AppDriveCtrl, SpeedLawReferenceIsShapedAndStoppedByTheDrive)
{
    cfg.speed_accel_rad_s2 = 1000.0f; // 0.05 rad/s per 50 us step
    cfg.stop_decel_rad_s2 = 2000.0f;
    cfg.stop_rest_rad_s = 1.0f;
    InitDrive();
    mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_CURRENT, false);
    c.uses_speed_ref = true;
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    law.out = mc_drive_out_t{};
    ASSERT_EQ(0, mc_drive_set_speed_ref(&d, 0.0f));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    ASSERT_EQ(0, mc_drive_set_speed_ref(&d, 0.2f)); // 4 steps of 0.05
    EXPECT_EQ(-EINVAL, mc_drive_set_speed_ref(&d, kNaN));
    float ref = 0.0f;
    for (int k = 0; k < 6; ++k) {
        GoodSample();
        (void)mc_drive_fast_step(&d);
        ASSERT_TRUE(law.last.have_speed_ref);
        // float sums of 0.05: to 1e-6 (a few ulp of 0.2)
        EXPECT_NEAR(ref, law.last.omega_ref_rad_s, 1e-6f) << k;
        const float a = (k < 4) ? 1000.0f : 0.0f;
        EXPECT_NEAR(a, law.last.alpha_ref_rad_s2, 1e-2f) << k;
        ref = (k < 3) ? ref + 1000.0f * kDt : 0.2f;
    }
    EXPECT_EQ(0.2f, d.speed_ref_rad_s);
    // a stop: the reference to 0 at 2000 rad/s^2 (0.1 rad/s per step: two
    // steps), the law running meanwhile, then the bridge opens
    ASSERT_EQ(0, mc_drive_stop(&d));
    ASSERT_EQ(MC_DRIVE_MODE_STOPPING, d.mode);
    const uint32_t fasts = law.fasts;
    for (uint32_t k = 0; k < 2u * cfg.slow_loop_div && d.mode == MC_DRIVE_MODE_STOPPING; ++k) {
        GoodSample();
        if (mc_drive_fast_step(&d)) {
            mc_drive_slow_step(&d);
        }
    }
    EXPECT_GT(law.fasts, fasts + 1u);
    EXPECT_EQ(0.0f, d.speed_ref_rad_s);
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
    EXPECT_FALSE(fake.pwm3.enabled);
}

// Dead-time compensation of the current loop: each leg's duty plus
// sat(i / band) dead_time / dt from the step's sample; against the same
// step without it (one float addition on a duty of order 0.5: 1e-6).
TEST_F(AppDriveCtrl, DeadTimeCompensationAddsEachLegsError)
{
    InitDrive();
    ASSERT_EQ(0, mc_drive_set_current_ref(&d, 0.0f, 3.0f));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 1.0f, -0.05f, 0.0f, kVbus, kMask3));
    (void)mc_drive_fast_step(&d);
    const float off[3] = {fake.pwm3.duty_a, fake.pwm3.duty_b, fake.pwm3.duty_c};
    cfg.dead_time_comp = true;
    cfg.dead_time_s = 1e-6f;
    cfg.dead_band_a = 0.1f;
    InitDrive();
    ASSERT_EQ(0, mc_drive_set_current_ref(&d, 0.0f, 3.0f));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 1.0f, -0.05f, 0.0f, kVbus, kMask3));
    (void)mc_drive_fast_step(&d);
    const float kd = 1e-6f / kDt;                              // 0.02
    EXPECT_NEAR(off[0] + kd * 1.0f, fake.pwm3.duty_a, 1e-6f);  // beyond the band: +1
    EXPECT_NEAR(off[1] + kd * -0.5f, fake.pwm3.duty_b, 1e-6f); // -0.05 / 0.1
    EXPECT_NEAR(off[2] + kd * -1.0f, fake.pwm3.duty_c, 1e-6f); // ic = -0.95: -1
    // refused: a dead time of half a period or more
    cfg.dead_time_s = 0.5f * kDt;
    EXPECT_EQ(MC_DRIVE_CFG_ERR_DEAD_TIME, mc_drive_check_cfg(&cfg));
}

// Enabling the current loop on a turning rotor: the first duties carry the
// back-EMF (omega_e flux along q, at the angle half a period after the next
// period's start), not the zero vector the rotor would drive its back-EMF
// into. Against the closed form through the same float kernels.
TEST_F(AppDriveCtrl, CurrentLoopStartsOnTheBackEmfOfATurningRotor)
{
    InitDrive();
    // turn the encoder at 2048 counts/step (about 7.7 rad/s electrical per
    // count... 80 rad/s mechanical at 20 kHz) until the tracking loop settles
    uint32_t count = 0;
    for (int k = 0; k < 4000; ++k) {
        count = (count + 13u) % fcfg.encoder_counts_per_rev;
        ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, count, MC_HAL_ENCODER_FLAG_VALID));
        GoodSample();
        (void)mc_drive_fast_step(&d);
    }
    const float w_m = d.enc_trk.omega_rad_s;
    ASSERT_NEAR(13.0 * 2 * 3.14159265 / fcfg.encoder_counts_per_rev / kDt, w_m, 0.01 * w_m);
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    const float w_e = w_m * static_cast<float>(kPolePairs);
    const float th = mc_wrap_2pi_f32(d.tm.theta_e_rad + 1.5f * w_e * kDt);
    float sn, cs, va, vb, da, db, dc;
    mc_sincos_f32(th, &sn, &cs);
    mc_inv_park_f32(0.0f, w_e * cfg.foc.flux_wb, sn, cs, &va, &vb);
    (void)mc_svpwm_f32(va, vb, kVbus, cfg.foc.limit_mode, &da, &db, &dc);
    EXPECT_EQ(da, fake.pwm3.duty_a);
    EXPECT_EQ(db, fake.pwm3.duty_b);
    EXPECT_EQ(dc, fake.pwm3.duty_c);
    EXPECT_GT(std::fabs(da - 0.5f), 1e-3f) << "not the zero vector";
}

// The regenerative limit is the drive's for every law that gives current
// references in the rotor's frame: a braking q reference (iq against the
// frame's speed) is scaled by (end - vbus) / (end - start) as the bus rises
// between the two thresholds, and the law is told the factor next step (its
// anti-windup tracks it). A motoring reference, or one outside the rotor's
// frame (rotor_frame false: I-f start), passes unscaled. Exact: one float
// product of the same operands as the drive's.
TEST_F(AppDriveCtrl, RegenLimitAppliesToCurrentLaws)
{
    cfg.vbus_regen_start_v = 30.0f;
    cfg.vbus_regen_end_v = 40.0f;
    InitDrive();
    mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_CURRENT);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    law.out = mc_drive_out_t{};
    law.out.iq_ref_a = 5.0f;
    law.out.omega_e_rad_s = -100.0f; // braking: iq against the speed
    law.out.rotor_frame = true;
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    const float vbus = 36.0f;
    const float k = (40.0f - vbus) / (40.0f - 30.0f); // 0.4
    auto step = [&]() {
        ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 0.0f, 0.0f, 0.0f, vbus, kMask3));
        (void)mc_drive_fast_step(&d);
    };
    step();
    EXPECT_EQ(k, d.tm.regen_scale);
    EXPECT_EQ(k * 5.0f, d.tm.iq_ref_a);
    step();
    EXPECT_EQ(k, law.last.regen_scale);
    EXPECT_EQ(k * 5.0f, law.last.iq_applied_a);
    // motoring: unscaled
    law.out.omega_e_rad_s = 100.0f;
    step();
    EXPECT_EQ(1.0f, d.tm.regen_scale);
    EXPECT_EQ(5.0f, d.tm.iq_ref_a);
    // not the rotor's frame: unscaled
    law.out.omega_e_rad_s = -100.0f;
    law.out.rotor_frame = false;
    step();
    EXPECT_EQ(1.0f, d.tm.regen_scale);
    EXPECT_EQ(5.0f, d.tm.iq_ref_a);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
}

// The DC-bus limits (mc_drive_bus.h) are the drive's for every law that
// gives current references: with the fake board's currents at zero the
// estimate's correction stays 0 and the limit is the model's root. At
// omega_e = -100 rad/s, psi 0.01 Wb, R 0.1 ohm, the braking reference 5 A
// would push 1.5 (R iq^2 + w psi iq) = -3.75 W into the bus: the
// regenerative limit 0.0625 A at 24 V (1.5 W) moves it to the root of
// 0.15 iq^2 - 1.5 iq + 1.5 = 0 nearer zero, (10 - sqrt 60) / 2; motoring at
// +100 rad/s the limit 0.25 A (6 W) to (-10 + sqrt 260) / 2; outside the
// rotor's frame the copper loss 3.75 W scales down to the limit 2.4 W:
// both references times 0.8. Tolerance 1e-5 relative: float roots.
TEST_F(AppDriveCtrl, BusLimitsApplyToCurrentLaws)
{
    cfg.bus.i_bus_regen_max_a = 0.0625f;
    cfg.bus.i_bus_max_a = 0.25f;
    InitDrive();
    mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_CURRENT);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    law.out = mc_drive_out_t{};
    law.out.iq_ref_a = 5.0f;
    law.out.omega_e_rad_s = -100.0f;
    law.out.rotor_frame = true;
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    auto step = [&]() {
        GoodSample();
        (void)mc_drive_fast_step(&d);
    };
    step();
    const double regen = (10.0 - std::sqrt(60.0)) / 2.0;
    EXPECT_NEAR(regen, d.tm.iq_ref_a, 1e-5 * regen);
    EXPECT_NEAR(0.0625f, d.bus.i_regen_lim_a, 1e-7);
    law.out.omega_e_rad_s = 100.0f;
    step();
    const double mot = (-10.0 + std::sqrt(260.0)) / 2.0;
    EXPECT_NEAR(mot, d.tm.iq_ref_a, 1e-5 * mot);
    cfg.bus.i_bus_max_a = 0.1f;
    mc_drive_set_runtime_limits(&d, &cfg);
    law.out.rotor_frame = false;
    law.out.id_ref_a = 0.0f;
    step();
    EXPECT_NEAR(4.0, d.tm.iq_ref_a, 1e-5 * 4.0);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
}

} // namespace
} // namespace apptest
