// Controlled stop (MC_DRIVE_MODE_STOPPING) on the fake HAL board: every stop
// path (stop command, CAN command timeout, over-temperature warning, bus-sag
// warning) decelerates the rotor to standstill at stop_decel_rad_s2 with the
// bridge on, and opens it in the first slow step at which the ramp is done
// and the estimated speed is at rest; critical faults (over-current,
// gate-driver fault, over-temperature trip, over-voltage) open it in the
// step that detects them, during a stop too.
//
// The rotor is a rigid inertia in the test (no friction, no load): torque
// kt * iq with the q current the drive commands applied ideally during the
// next period (an ideal current loop with the one-period delay of a real
// drive); torque 0 while the bridge is open. The fake ADC returns those
// phase currents, the fake encoder the rotor's angle (16384 counts/rev).
#include <cmath>
#include <vector>

#include "app_test_fixture.h"
#include "mc_record.hpp"
#include "mc_can_cmd.h"

using namespace apptest;

namespace
{

// Rotor and stop configuration: kt = 1.5 p flux = 0.06 Nm/A (GoodCfg:
// 4 pole pairs, 10 mWb), J = 1e-4 kg m^2: 500 rad/s^2 takes
// J decel / kt = 0.833 A, well inside i_max (20 A).
constexpr double kJ = 1.0e-4;
constexpr double kKt = 1.5 * kPolePairs * 0.01;
constexpr float kDecel = 500.0f;  // [rad/s^2]
constexpr float kRest = 1.0f;     // [rad/s]
constexpr float kStopKp = 0.05f;  // [A/(rad/s)]: loop crossover kp kt / J = 30 rad/s
constexpr double kOmega0 = 100.0; // starting speed [rad/s]: 0.2 s stop
constexpr double kPi = 3.14159265358979323846;

struct StopTrace {
    std::vector<double> t_s, omega; // plant speed after each fast step
    long start_step = -1;           // fast step in which STOPPING began
    long open_step = -1;            // fast step after which the bridge was open
    long first_ready_slow = -1;     // first slow step with ramp 0 and |omega_est| <= rest
    bool bridge_on_while_stopping = true;
    double omega_at_open = 0.0;
    bool opened_on_crossing = false; // the estimate had crossed zero when it opened
    double omega_back = 0.0;         // largest rotor speed against kOmega0's sign
};

class AppStop : public AppDrive
{
  protected:
    void SetUp() override
    {
        AppDrive::SetUp();
        cfg.stop_decel_rad_s2 = kDecel;
        cfg.stop_rest_rad_s = kRest;
        cfg.stop_kp_a_s_rad = kStopKp;
        cfg.stop_iq_ff_a = static_cast<float>(kJ * kDecel / kKt);
    }

    // Fake ADC and encoder from the rotor's state; then one fast step (and
    // the slow step when due). Returns true when a slow step ran.
    bool Step(float vbus_v = kVbus, float extra_ia_a = 0.0f)
    {
        const double th_e = kPolePairs * theta_ + kOffset;
        const double ial = -iq_applied_ * std::sin(th_e);
        const double ibe = iq_applied_ * std::cos(th_e);
        const float ia = static_cast<float>(ial) + extra_ia_a;
        const float ib = static_cast<float>(-0.5 * ial + 0.5 * std::sqrt(3.0) * ibe);
        EXPECT_EQ(0, mc_hal_fake_adc_set_sample(&fake, ia, ib, 0.0f, vbus_v, kMask3));
        const double turns = theta_ / (2.0 * kPi);
        const double frac = turns - std::floor(turns);
        const auto cpr = static_cast<double>(fcfg.encoder_counts_per_rev);
        uint32_t count = static_cast<uint32_t>(std::floor(frac * cpr));
        count = (count >= fcfg.encoder_counts_per_rev) ? 0u : count;
        EXPECT_EQ(0, mc_hal_fake_encoder_set(&fake, count, MC_HAL_ENCODER_FLAG_VALID));
        const bool slow = mc_drive_fast_step(&d);
        if (slow) {
            ready_before_slow_ = d.mode == MC_DRIVE_MODE_STOPPING &&
                                 d.stop_omega_ref_rad_s == 0.0f &&
                                 std::fabs(d.enc_trk.omega_rad_s) <= kRest;
            mc_drive_slow_step(&d);
            if (can_ != nullptr) {
                mc_can_cmd_step(can_);
            }
        }
        // The q current of this step acts during the next period.
        iq_applied_ = fake.pwm3.enabled ? d.tm.iq_ref_a : 0.0;
        omega_ += kKt * iq_applied_ / kJ * kDt;
        theta_ += omega_ * kDt;
        ++step_;
        return slow;
    }

    // CURRENT mode at zero torque with the rotor coasting at omega, long
    // enough (0.1 s = 50 / bw) for the speed estimate to settle.
    void SpinUp(double omega = kOmega0)
    {
        InitDrive();
        omega_ = omega;
        ASSERT_EQ(0, mc_drive_set_current_ref(&d, 0.0f, 0.0f));
        ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
        for (int k = 0; k < 2000; ++k) {
            Step();
        }
        ASSERT_EQ(MC_DRIVE_MODE_CURRENT, d.mode);
        // the tracking loop has converged: 0.1 % (encoder quantisation)
        ASSERT_NEAR(omega, d.enc_trk.omega_rad_s, 1e-3 * omega);
    }

    // Run until the bridge opens (at most 0.5 s) and trace the stop; the
    // stop must begin within `start_within` fast steps of the call.
    StopTrace RunStop(long start_within, float vbus_v = kVbus)
    {
        StopTrace tr;
        const long first = step_;
        for (long k = 0; k < 10000 && fake.pwm3.enabled; ++k) {
            const bool slow = Step(vbus_v);
            if (tr.start_step < 0 && d.mode == MC_DRIVE_MODE_STOPPING) {
                tr.start_step = step_;
            }
            if (slow && ready_before_slow_ && tr.first_ready_slow < 0) {
                tr.first_ready_slow = step_;
            }
            if (tr.start_step >= 0) {
                tr.omega_back = std::max(tr.omega_back, -omega_);
                tr.t_s.push_back(static_cast<double>(step_ - tr.start_step) * kDt);
                tr.omega.push_back(omega_);
                if (fake.pwm3.enabled != (d.mode == MC_DRIVE_MODE_STOPPING)) {
                    tr.bridge_on_while_stopping = false;
                }
            }
        }
        if (!fake.pwm3.enabled) {
            tr.open_step = step_;
            tr.omega_at_open = omega_;
            tr.opened_on_crossing = d.enc_trk.omega_rad_s < 0.0f;
        }
        EXPECT_GE(tr.start_step, first + 1);
        EXPECT_LE(tr.start_step, first + start_within);
        return tr;
    }

    // Least-squares slope of omega(t) while it falls from 80 % to 20 % of
    // kOmega0 (the ramp's straight part).
    static double DecelRate(const StopTrace &tr)
    {
        double n = 0, st = 0, sw = 0, stt = 0, stw = 0;
        for (size_t i = 0; i < tr.t_s.size(); ++i) {
            if (tr.omega[i] <= 0.8 * kOmega0 && tr.omega[i] >= 0.2 * kOmega0) {
                n += 1;
                st += tr.t_s[i];
                sw += tr.omega[i];
                stt += tr.t_s[i] * tr.t_s[i];
                stw += tr.t_s[i] * tr.omega[i];
            }
        }
        return -(n * stw - st * sw) / (n * stt - st * st);
    }

    // What every controlled stop must show.
    void ExpectControlledStop(const StopTrace &tr, uint32_t cause)
    {
        ASSERT_GE(tr.start_step, 0) << "no controlled stop";
        ASSERT_GE(tr.open_step, 0) << "the bridge never opened";
        EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
        EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
        EXPECT_EQ(cause, d.stop_cause);
        // The bridge stays on for the whole deceleration.
        EXPECT_TRUE(tr.bridge_on_while_stopping);
        // Rate: the ramp is exact and the feed-forward carries the whole
        // deceleration; what is left is the P loop's correction of the
        // speed estimate's quantisation noise (16384 counts/rev at 20 kHz)
        // and of the one-period delay: 1 % of the rate (measured 0.08 %
        // below it).
        const double rate = DecelRate(tr);
        EXPECT_NEAR(kDecel, rate, 0.01 * kDecel);
        // Time to standstill: the ramp takes omega0 / decel. It starts from
        // the speed estimate, not the rotor's speed (their difference and the
        // float ramp's 0.025 rad/s steps: within one slow period, 0.5 ms, of
        // the ramp time); it ends in the first slow step (every 0.5 ms) at
        // which the estimate is at rest after the ramp, the feed-forward
        // keeping the rotor on the ramp: at most 2 ms late (measured: -0.05
        // .. +0.5 ms).
        const double t_pred = kOmega0 / kDecel;
        const double t_stop = static_cast<double>(tr.open_step - tr.start_step) * kDt;
        EXPECT_GE(t_stop, t_pred - 0.0005);
        EXPECT_LE(t_stop, t_pred + 0.002);
        // The step in which the bridge opens: the first slow step at which
        // the ramp is at 0 and the estimate at rest, or earlier the fast step
        // in which the estimate crossed zero (a stop never reverses).
        if (tr.opened_on_crossing) {
            EXPECT_TRUE(tr.first_ready_slow < 0 || tr.open_step <= tr.first_ready_slow);
        } else {
            EXPECT_EQ(tr.first_ready_slow, tr.open_step);
        }
        // Never backwards by more than the crossing's period and the one its
        // current acts in: 2 decel T = 0.05 rad/s.
        EXPECT_LE(tr.omega_back, 2.0 * kDecel * kDt);
        // At rest when it opens: the estimate's bound; the rotor may differ
        // from the estimate by its lag and quantisation, 0.1 rad/s (measured
        // |omega| <= 0.015 rad/s).
        EXPECT_LE(std::fabs(tr.omega_at_open), kRest + 0.1);
        rate_ = rate;
        t_stop_ = t_stop;
    }

    double omega_ = 0.0, theta_ = 0.0, iq_applied_ = 0.0;
    long step_ = 0;
    bool ready_before_slow_ = false;
    mc_can_cmd_t *can_ = nullptr;
    double rate_ = 0.0, t_stop_ = 0.0;
};

TEST_F(AppStop, StopCommandDeceleratesAtTheConfiguredRate)
{
    SpinUp();
    ASSERT_EQ(0, mc_drive_stop(&d));
    ASSERT_EQ(MC_DRIVE_MODE_STOPPING, d.mode);
    const StopTrace tr = RunStop(1);
    ExpectControlledStop(tr, MC_DRIVE_STOP_CMD);
    mc_record("decel_rad_s2", rate_, 0.01 * kDecel);
    mc_record("t_stop_over_pred", t_stop_ / (kOmega0 / kDecel), 1.0 + 0.002 / (kOmega0 / kDecel));
}

// CURRENT (torque) mode over CAN: the command timeout ramps the torque to
// zero at stop_ramp_a_per_s, then opens the bridge; the drive's
// speed-controlled stop (configured here) is not used: the host owned the
// torque, not the speed, and a speed-controlled stop would brake against
// (or drive with) whatever the load does. SPEED and POSITION stop under
// control (the drive's STOPPING: tests/sil/position/test_stop_sil.cpp).
TEST_F(AppStop, CanCommandTimeoutInTorqueModeRampsTheTorqueDown)
{
    SpinUp();
    mc_can_cmd_cfg_t cc{};
    cc.node_id = 1;
    cc.tick_hz = 2000; // mc_can_cmd_step in the slow loop: 20 kHz / 10
    cc.timeout_s = 0.05f;
    cc.stop_ramp_a_per_s = 100.0f;
    cc.stop_decel_rad_s2 = kDecel;
    cc.speed_max_rad_s = 200.0f;
    cc.speed_drive_mode = MC_DRIVE_MODE_CURRENT;
    cc.position_drive_mode = MC_DRIVE_MODE_IDLE;
    mc_can_cmd_t c{};
    ASSERT_EQ(MC_CAN_CMD_CFG_OK, mc_can_cmd_init(&c, &cc, &d, nullptr));
    ASSERT_GT(d.cfg.stop_decel_rad_s2, 0.0f) << "the controlled stop is configured";
    // control mode CURRENT (0x11), enable (0x10), then 2 A of q current
    mc_hal_can_frame_t f{};
    f.id = (1u << 5) | 0x11u;
    f.len = 1;
    f.data[0] = 1;
    ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_cmd_handle(&c, &f, &fake.can_dev));
    f.id = (1u << 5) | 0x10u;
    ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_cmd_handle(&c, &f, &fake.can_dev));
    ASSERT_TRUE(c.enabled);
    ASSERT_EQ(MC_DRIVE_MODE_CURRENT, d.mode);
    ASSERT_EQ(0, mc_drive_set_current_ref(&d, 0.0f, 2.0f));
    can_ = &c;
    // No keep-alive: the timeout (100 slow ticks = 1000 fast steps), then
    // 2 A at 100 A/s = 20 ms = 40 slow ticks down to 0.
    std::vector<float> iq; // the q reference at each slow step of the stop
    bool entered_stopping = false;
    long steps = 0;
    while (c.enabled && steps < 4000) {
        if (Step() && c.stopping) {
            iq.push_back(d.iq_ref_a);
        }
        entered_stopping = entered_stopping || (d.mode == MC_DRIVE_MODE_STOPPING);
        ++steps;
    }
    EXPECT_FALSE(c.enabled);
    EXPECT_EQ(MC_CAN_STOP_CMD_TIMEOUT, c.stop_reason);
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
    EXPECT_FALSE(fake.pwm3.enabled) << "the bridge is open at the end of the ramp";
    EXPECT_FALSE(entered_stopping) << "no speed-controlled stop in torque mode";
    EXPECT_GE(c.ticks_since_alive, 100u);
    // 40 ticks of ramp (+1: the tick that reaches 0 ends the run)
    ASSERT_GE(iq.size(), 40u);
    ASSERT_LE(iq.size(), 41u);
    // the ramp: 0.05 A per 0.5 ms slow tick (float steps: to 1e-5 A each)
    EXPECT_NEAR(2.0f - iq[0], 0.05f, 1e-5f);
    for (size_t k = 1; k < 39; ++k) {
        EXPECT_NEAR(iq[k - 1] - iq[k], 0.05f, 1e-5f) << k;
    }
    // never below zero: the ramp never reverses the torque
    for (float x : iq) {
        EXPECT_GE(x, 0.0f);
    }
    EXPECT_EQ(0.0f, d.iq_ref_a);
    can_ = nullptr;
}

TEST_F(AppStop, OverTemperatureWarningDeceleratesAtTheConfiguredRate)
{
    cfg.temp_max_c = 100.0f;
    cfg.temp_warn_c = 80.0f;
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 40.0f, 40.0f, MC_HAL_ADC_TEMP_VALID_ALL));
    SpinUp();
    // warm, not hot: a warning, not the trip
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 85.0f, 40.0f, MC_HAL_ADC_TEMP_VALID_ALL));
    const StopTrace tr = RunStop(kSlowDiv); // read in the next slow step
    ExpectControlledStop(tr, MC_DRIVE_STOP_WARNING);
    EXPECT_EQ(MC_DRIVE_WARN_TEMP, d.warnings);
    // CURRENT is refused until the warning is cleared
    EXPECT_EQ(-EBUSY, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
}

TEST_F(AppStop, BusSagWarningDeceleratesAtTheConfiguredRate)
{
    cfg.vbus_sag_v = 18.0f; // trip at 10 V (vbus_min_v)
    SpinUp();
    const StopTrace tr = RunStop(kSlowDiv, 15.0f);
    ExpectControlledStop(tr, MC_DRIVE_STOP_WARNING);
    EXPECT_EQ(MC_DRIVE_WARN_VBUS_SAG, d.warnings);
}

// A critical fault opens the bridge in the step that detects it: the fast
// step for a measurement, the slow step for the supervised inputs.
TEST_F(AppStop, OverCurrentOpensTheBridgeInTheSameFastStep)
{
    SpinUp();
    ASSERT_EQ(0, mc_drive_stop(&d));
    for (int k = 0; k < 400; ++k) { // 20 ms into the stop
        Step();
    }
    ASSERT_EQ(MC_DRIVE_MODE_STOPPING, d.mode);
    ASSERT_TRUE(fake.pwm3.enabled);
    const double omega_before = omega_;
    Step(kVbus, kITrip + 1.0f);
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_EQ(MC_DRIVE_FAULT_OVERCURRENT, d.first_fault);
    // far from standstill: it did not wait for the rotor (10 ms at 500
    // rad/s^2 is 5 rad/s of the 100)
    EXPECT_GT(omega_before, 0.8 * kOmega0);
}

TEST_F(AppStop, OverVoltageOpensTheBridgeInTheSameFastStep)
{
    SpinUp();
    ASSERT_EQ(0, mc_drive_stop(&d));
    Step();
    ASSERT_TRUE(fake.pwm3.enabled);
    Step(kVbusMax + 1.0f);
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_EQ(MC_DRIVE_FAULT_VBUS_HIGH, d.first_fault);
}

TEST_F(AppStop, GateFaultOpensTheBridgeInTheSlowStepThatReadsIt)
{
    fcfg.fault_input_kills = false;               // nFAULT not wired to the break input:
    ASSERT_EQ(0, mc_hal_fake_init(&fake, &fcfg)); // the drive must react itself
    SpinUp();
    ASSERT_EQ(0, mc_drive_stop(&d));
    while (!Step()) {
    }
    ASSERT_EQ(0, mc_hal_fake_fault_set_inputs(&fake, MC_HAL_FAULT_GATE_DRIVER));
    int steps = 0;
    bool slow = false;
    while (fake.pwm3.enabled && steps < 100) {
        slow = Step();
        ++steps;
    }
    // the next slow step (kSlowDiv fast steps later) reads it and opens
    EXPECT_EQ(static_cast<int>(kSlowDiv), steps);
    EXPECT_TRUE(slow);
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_EQ(MC_DRIVE_FAULT_HW_INPUT, d.first_fault);
    EXPECT_EQ(0u, fake.gate_kill_count); // the PWM driver confirmed the disable
}

TEST_F(AppStop, OverTemperatureTripOpensTheBridgeInTheSlowStepThatReadsIt)
{
    cfg.temp_max_c = 100.0f;
    cfg.temp_warn_c = 80.0f;
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 40.0f, 40.0f, MC_HAL_ADC_TEMP_VALID_ALL));
    SpinUp();
    while (!Step()) {
    }
    // from cool to beyond the trip between two slow steps: the trip wins
    // over the warning's controlled stop
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 40.0f, 120.0f, MC_HAL_ADC_TEMP_VALID_ALL));
    int steps = 0;
    while (fake.pwm3.enabled && steps < 100) {
        Step();
        ++steps;
    }
    EXPECT_EQ(static_cast<int>(kSlowDiv), steps);
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_EQ(MC_DRIVE_FAULT_OVERTEMP, d.first_fault);
    EXPECT_NEAR(kOmega0, omega_, 1e-9); // no braking torque was applied
}

// Without a controlled stop configured every path opens the bridge at once.
TEST_F(AppStop, NoDecelerationConfiguredOpensAtOnce)
{
    cfg.stop_decel_rad_s2 = 0.0f;
    SpinUp();
    ASSERT_EQ(0, mc_drive_stop(&d));
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
}

} // namespace

// ---------------------------------------------------------------------------
// Active short circuit (mc_drive_cfg_t.asc_enable). The fake board's motor:
// flux 10 mWb, 4 pole pairs: line-to-line back-EMF peak sqrt(3) p flux omega
// = 0.0693 V per rad/s, above the 24 V bus from 346.4 rad/s (the exit at 0.9
// of the bus: 311.8 rad/s). Ld = 1 mH: short-circuit current flux / Ld =
// 10 A, below the 30 A trip. (The test's rotor feels no torque in FAULT:
// the fake board does not model the short's braking; the speeds are set.)
namespace
{

constexpr double kEmfPerRadS = 1.7320508075688772 * kPolePairs * 0.01;

class AppAsc : public AppStop
{
  protected:
    void SetUp() override
    {
        AppStop::SetUp();
        cfg.foc.ld_h = 1.0e-3f;
        cfg.foc.lq_h = 1.0e-3f;
        cfg.asc_enable = true;
    }
    bool Shorted() const
    {
        return fake.pwm3.enabled && fake.pwm3.duty_a == 0.0f && fake.pwm3.duty_b == 0.0f &&
               fake.pwm3.duty_c == 0.0f;
    }
};

TEST_F(AppAsc, InitRefusesAShortCircuitCurrentAtOrAboveTheTrip)
{
    cfg.foc.ld_h = 0.01f / kITrip; // flux / Ld = i_trip exactly
    EXPECT_EQ(MC_DRIVE_CFG_ERR_ASC, mc_drive_init(&d, &cfg, hal));
    cfg.foc.ld_h = 1.0e-3f;
    cfg.foc.flux_wb = 0.0f; // no magnet model: cannot judge the back-EMF
    EXPECT_EQ(MC_DRIVE_CFG_ERR_ASC, mc_drive_init(&d, &cfg, hal));
    cfg.foc.flux_wb = 0.01f;
    EXPECT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &cfg, hal));
}

// Above the speed where the back-EMF exceeds the bus: the fault shorts the
// phases in the step that detects it, IDLE keeps the short, and the bridge
// opens in the first fast step whose speed estimate is below the exit.
TEST_F(AppAsc, FaultAboveTheBusSpeedShortsThenOpensBelowTheExitSpeed)
{
    SpinUp(400.0); // back-EMF 27.7 V > 24 V
    mc_drive_raise_fault(&d, MC_DRIVE_FAULT_EXTERNAL);
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_TRUE(d.asc_active);
    EXPECT_TRUE(Shorted());
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_IDLE));
    EXPECT_TRUE(Shorted()) << "IDLE in FAULT keeps the short";
    for (int k = 0; k < 100; ++k) {
        Step();
    }
    EXPECT_TRUE(Shorted());
    // the rotor slows (as under the short's braking) through the exit speed
    omega_ = 300.0;
    long steps = 0;
    double est_at_open = 0.0;
    while (Shorted() && steps < 2000) {
        Step();
        ++steps;
        est_at_open = d.enc_trk.omega_rad_s;
    }
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_FALSE(d.asc_active);
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    // opened in the first step whose estimate is below the exit speed:
    // within one period's change of the estimate (at most its 100 rad/s
    // step response's largest slope, bw * 100 rad/s * dt = 2.5 rad/s)
    const double w_exit = 0.9 * kVbus / kEmfPerRadS;
    EXPECT_LE(est_at_open, w_exit);
    EXPECT_GE(est_at_open, w_exit - 2.5);
}

TEST_F(AppAsc, FaultBelowTheBusSpeedOpensTheBridge)
{
    SpinUp(300.0); // back-EMF 20.8 V < 24 V: opening pumps nothing
    mc_drive_raise_fault(&d, MC_DRIVE_FAULT_EXTERNAL);
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_FALSE(d.asc_active);
}

TEST_F(AppAsc, CriticalFaultsOpenTheBridgeEvenAboveTheBusSpeed)
{
    SpinUp(400.0);
    Step(kVbus, kITrip + 1.0f); // over-current: the bridge itself is suspect
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_FALSE(d.asc_active);
    EXPECT_EQ(MC_DRIVE_FAULT_OVERCURRENT, d.first_fault);
}

TEST_F(AppAsc, OverCurrentDuringTheShortOpensItInTheSameStep)
{
    SpinUp(400.0);
    mc_drive_raise_fault(&d, MC_DRIVE_FAULT_EXTERNAL);
    Step();
    ASSERT_TRUE(Shorted());
    Step(kVbus, kITrip + 1.0f); // the short's current beyond the trip
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_FALSE(d.asc_active);
    EXPECT_EQ(MC_DRIVE_FAULT_EXTERNAL | MC_DRIVE_FAULT_OVERCURRENT, d.faults);
}

TEST_F(AppAsc, ClearFaultsEndsTheShort)
{
    SpinUp(400.0);
    mc_drive_raise_fault(&d, MC_DRIVE_FAULT_EXTERNAL);
    ASSERT_TRUE(Shorted());
    EXPECT_EQ(0, mc_drive_clear_faults(&d));
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_FALSE(d.asc_active);
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
}

TEST_F(AppAsc, OffByDefault)
{
    cfg.asc_enable = false;
    SpinUp(400.0);
    mc_drive_raise_fault(&d, MC_DRIVE_FAULT_EXTERNAL);
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_FALSE(d.asc_active);
}

} // namespace
