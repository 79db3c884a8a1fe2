// Power-up alignment and index search plugged into the drive on the fake
// HAL board. The rotor is written here: J theta'' = k i sin(theta_cmd -
// p theta) - B theta' - load - Coulomb friction (sticking at rest), with
// k = 3/2 p psi (the torque per ampere of a current at 90 degrees to the
// flux), integrated in sub-steps; the current loop is taken as ideal (the
// samples are the commanded vector), the encoder counts from the power-up
// angle (an incremental encoder), the index a mark at a mechanical angle.
#include <gtest/gtest.h>

#include <cerrno>
#include <cmath>

#include "app_test_fixture.h"
#include "mc_ctrl_align.h"

namespace
{

using apptest::GoodCfg;
using apptest::kDt;
using apptest::kPolePairs;
using apptest::kVbus;

constexpr double kPi = 3.14159265358979323846;
constexpr uint32_t kCpr = 16384u; // the fake board's
constexpr double kFlux = 0.01;    // GoodCfg's
constexpr double kJ = 1.0e-5;     // kg m^2
constexpr double kB = 2.0e-3;     // N m s/rad: damping ratio ~0.3 at 5 A
constexpr int kSub = 10;

double wrap_2pi(double x)
{
    double w = std::fmod(x, 2.0 * kPi);
    return (w < 0.0) ? w + 2.0 * kPi : w;
}

double wrap_pi(double x)
{
    return wrap_2pi(x + kPi) - kPi;
}

struct Rotor {
    double th = 0.0, w = 0.0; // mechanical
    double load_nm = 0.0;
    double coulomb_nm = 0.0;
    int pole_pairs = static_cast<int>(kPolePairs);
    double stop_lo = -1e9, stop_hi = 1e9; // end stops [rad mech.]
    bool jammed = false;
    double b_nms = kB;
    double j = kJ;

    // id along the vector, iq 90 degrees ahead of it.
    void advance(double theta_cmd_e, double i_a, double iq_a, double dt)
    {
        if (jammed) {
            w = 0.0;
            return;
        }
        const double k = 1.5 * pole_pairs * kFlux;
        const double h = dt / kSub;
        for (int n = 0; n < kSub; ++n) {
            const double delta = theta_cmd_e - pole_pairs * th;
            const double drive = k * (i_a * std::sin(delta) + iq_a * std::cos(delta)) - load_nm;
            double fr = 0.0;
            if (std::fabs(w) < 1e-4 && std::fabs(drive) <= coulomb_nm) {
                w = 0.0; // stuck
                continue;
            }
            fr = (w != 0.0) ? std::copysign(coulomb_nm, w) : std::copysign(coulomb_nm, drive);
            w += h * (drive - b_nms * w - fr) / j;
            th += h * w;
            if (th < stop_lo || th > stop_hi) {
                th = std::fmin(std::fmax(th, stop_lo), stop_hi);
                w = 0.0;
            }
        }
    }
};

// The drive on the fake board with a plug-in; the rotor feeds the samples.
struct Bench {
    mc_hal_fake_config_t fcfg{};
    mc_hal_fake_t fake{};
    mc_drive_cfg_t cfg = GoodCfg();
    mc_drive_t d{};
    Rotor rotor;
    double th_power_up = 0.0; // the encoder counts from here
    bool reversed_wiring = false;
    bool has_index = false;
    double index_at = 0.0; // mechanical angle of the mark
    bool index_seen = false;
    uint32_t index_count = 0u;

    double rotor_j = kJ;
    void init(double theta0)
    {
        rotor.j = rotor_j;
        ASSERT_EQ(0, mc_hal_fake_config_default(&fcfg));
        ASSERT_EQ(0, mc_hal_fake_init(&fake, &fcfg));
        cfg.encoder_offset_rad = 0.0f; // unknown: what the alignment finds
        ASSERT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &cfg, &fake.board));
        rotor.th = theta0;
        th_power_up = theta0;
        sample(0.0, 0.0);
    }
    // The encoder (incremental: counts from power-up; after the index,
    // referenced to it, as the HAL reports) and the currents of the vector.
    void sample(double theta_cmd_e, double i_a, double iq_a = 0.0)
    {
        const double dir = reversed_wiring ? -1.0 : 1.0;
        const double rel = dir * (rotor.th - th_power_up);
        auto cnt = [](double a) {
            const double c = std::floor(a * kCpr / (2.0 * kPi));
            const long long m = static_cast<long long>(c) % static_cast<long long>(kCpr);
            return static_cast<uint32_t>(m < 0 ? m + kCpr : m);
        };
        uint32_t count = cnt(rel);
        uint32_t flags = MC_HAL_ENCODER_FLAG_VALID;
        if (has_index && !index_seen) {
            // the mark crossed since the last sample (either way)
            const double a = std::floor((last_th - index_at) / (2.0 * kPi));
            const double b = std::floor((rotor.th - index_at) / (2.0 * kPi));
            if (a != b) {
                index_seen = true;
                index_count = cnt(dir * (index_at + 2.0 * kPi * std::fmax(a, b) - th_power_up));
            }
        }
        if (index_seen) {
            count = (count + kCpr - index_count) % kCpr;
            flags |= MC_HAL_ENCODER_FLAG_INDEX;
        }
        last_th = rotor.th;
        ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, count, flags));
        const double ial = i_a * std::cos(theta_cmd_e) - iq_a * std::sin(theta_cmd_e);
        const double ibe = i_a * std::sin(theta_cmd_e) + iq_a * std::cos(theta_cmd_e);
        const double ia = ial;
        const double ib = -0.5 * ial + 0.5 * std::sqrt(3.0) * ibe;
        ASSERT_EQ(0,
                  mc_hal_fake_adc_set_sample(&fake, static_cast<float>(ia), static_cast<float>(ib),
                                             static_cast<float>(-ia - ib), kVbus, apptest::kMask3));
    }
    void step(const mc_ctrl_align_vec_t &v)
    {
        (void)mc_drive_fast_step(&d);
        th_lo = std::fmin(th_lo, rotor.th - th_power_up);
        th_hi = std::fmax(th_hi, rotor.th - th_power_up);
        if (d.mode != MC_DRIVE_MODE_CTRL) {
            rotor.advance(0.0, 0.0, 0.0, kDt);
            sample(0.0, 0.0);
            return;
        }
        i_peak = std::fmax(
            i_peak, std::hypot(static_cast<double>(v.i_cmd_a), static_cast<double>(v.iq_cmd_a)));
        iq_peak = std::fmax(iq_peak, std::fabs(static_cast<double>(v.iq_cmd_a)));
        rotor.advance(v.theta_cmd_e_rad, v.i_cmd_a, v.iq_cmd_a, kDt);
        sample(v.theta_cmd_e_rad, v.i_cmd_a, v.iq_cmd_a);
    }
    double last_th = 0.0;
    // what the plug-in commanded and where the rotor went (from power-up)
    double i_peak = 0.0, iq_peak = 0.0;
    double th_lo = 0.0, th_hi = 0.0; // [rad mech.]
};

mc_ctrl_align_cfg_t align_cfg(const mc_drive_cfg_t &dc)
{
    mc_ctrl_align_cfg_t c{};
    c.foc = dc.foc;
    c.pole_pairs = kPolePairs;
    c.i_max_a = dc.i_max_a;
    c.i_align_a = 5.0f;
    c.t_ramp_s = 0.05f;
    c.t_settle_s = 0.05f;
    c.t_timeout_s = 1.0f;
    c.still_band_m_rad = 4.0f * 6.2831853f / 16384.0f; // 4 counts
    c.sweep_e_rad = static_cast<float>(kPi / 2.0);
    c.omega_sweep_e_rad_s = 20.0f;
    c.sweep_tol_e_rad = 0.2f;
    c.load_tol_e_rad = 0.05f;
    c.travel_max_m_rad = static_cast<float>(1.5 * (kPi + 1.5 * kPi) / kPolePairs);
    return c;
}

// Run the alignment until it leaves RUNNING (or the drive faults).
mc_ctrl_align_result_t run_align(Bench &b, mc_ctrl_align_t &al, int n_max = 60000,
                                 float damping = 0.0f)
{
    mc_ctrl_align_cfg_t c = align_cfg(b.cfg);
    c.damping_a_s_rad = damping;
    EXPECT_EQ(mc_ctrl_align_init(&al, &c), MC_CTRL_ALIGN_ERR_NONE);
    EXPECT_EQ(0, mc_drive_attach_ctrl(&b.d, mc_ctrl_align_ops(&al)));
    EXPECT_EQ(0, mc_drive_set_mode(&b.d, MC_DRIVE_MODE_CTRL));
    mc_ctrl_align_result_t r{};
    for (int n = 0; n < n_max; ++n) {
        b.step(al.v);
        (void)mc_ctrl_align_get_result(&al, &r);
        if (r.status != MC_CTRL_ALIGN_RUNNING) {
            break;
        }
    }
    return r;
}

// The offset the drive needs: theta_e = p theta_m(count) + offset, with the
// encoder counting from the power-up angle: offset = p theta_power_up.
double true_offset(const Bench &b)
{
    return wrap_2pi(kPolePairs * b.th_power_up);
}

} // namespace

TEST(CtrlAlign, InitRefusesOutOfRange)
{
    const mc_drive_cfg_t dc = GoodCfg();
    mc_ctrl_align_t al{};
    const mc_ctrl_align_cfg_t good = align_cfg(dc);
    ASSERT_EQ(mc_ctrl_align_init(&al, &good), MC_CTRL_ALIGN_ERR_NONE);
    auto refused = [&](auto mutate) {
        mc_ctrl_align_cfg_t c = good;
        mutate(c);
        mc_ctrl_align_t x{};
        return mc_ctrl_align_init(&x, &c) == MC_CTRL_ALIGN_ERR_CFG;
    };
    EXPECT_TRUE(refused([](mc_ctrl_align_cfg_t &c) { c.i_align_a = 25.0f; })); // above i_max
    EXPECT_TRUE(refused([](mc_ctrl_align_cfg_t &c) { c.i_align_a = 0.0f; }));
    EXPECT_TRUE(refused([](mc_ctrl_align_cfg_t &c) { c.i_align_a = apptest::kNaN; }));
    EXPECT_TRUE(refused([](mc_ctrl_align_cfg_t &c) { c.pole_pairs = 0u; }));
    EXPECT_TRUE(refused([](mc_ctrl_align_cfg_t &c) { c.t_ramp_s = 10.0f; }));
    EXPECT_TRUE(refused([](mc_ctrl_align_cfg_t &c) { c.t_timeout_s = 0.01f; })); // < settle
    EXPECT_TRUE(refused([](mc_ctrl_align_cfg_t &c) { c.sweep_e_rad = 2.0f; }));
    EXPECT_TRUE(refused([](mc_ctrl_align_cfg_t &c) { c.sweep_tol_e_rad = 1.0f; })); // > s/2
    EXPECT_TRUE(refused([](mc_ctrl_align_cfg_t &c) { c.load_tol_e_rad = 1.0f; }));
    EXPECT_TRUE(refused([](mc_ctrl_align_cfg_t &c) { c.omega_sweep_e_rad_s = 0.0f; }));
    // travel below what the procedure itself needs: 1.25 (pi + 3 s) / p
    EXPECT_TRUE(refused([](mc_ctrl_align_cfg_t &c) { c.travel_max_m_rad = 1.0f; }));
    mc_ctrl_align_cfg_t bad_foc = good;
    bad_foc.foc.dt_s = -1.0f;
    EXPECT_EQ(mc_ctrl_align_init(&al, &bad_foc), MC_CTRL_ALIGN_ERR_CFG);
    EXPECT_EQ(mc_ctrl_align_init(nullptr, &good), MC_CTRL_ALIGN_ERR_NULL);
}

// Power-ups at rotor angles all round the turn (the encoder counts from
// there): the offset found matches the truth. Tolerance: the count's
// resolution (4 x 2 pi / 16384 = 1.5e-3 rad el.) plus what the rotor still
// moves once |omega| < omega_still for t_settle (< 0.05 rad/s x ... a few
// mrad): 0.01 rad el.
TEST(CtrlAlign, OffsetAtAnyPowerUpAngle)
{
    for (int k = 0; k < 8; ++k) {
        Bench b;
        b.init(0.37 + k * 2.0 * kPi / 8.0 / kPolePairs * 3.1); // spread over electrical turns
        mc_ctrl_align_t al{};
        const mc_ctrl_align_result_t r = run_align(b, al);
        ASSERT_EQ(r.status, MC_CTRL_ALIGN_DONE) << k << " fail " << r.fail;
        EXPECT_NEAR(wrap_pi(r.offset_e_rad - true_offset(b)), 0.0, 0.01) << k;
        EXPECT_NEAR(r.sweep_e_rad, kPi / 2.0, 0.01);
        // the snap (half an electrical turn at most) and the sweeps (3 s)
        EXPECT_LE(r.travel_peak_m_rad, (kPi + 1.5 * kPi) / kPolePairs);
        EXPECT_EQ(b.d.faults, 0u);
        // the current is released at the end
        EXPECT_EQ(al.v.i_cmd_a, 0.0f);
    }
}

// The unstable equilibrium: the rotor exactly opposite the first vector
// (no torque from it); the sweep moves the vector off the dead point.
TEST(CtrlAlign, RotorOppositeTheFirstVector)
{
    Bench b;
    b.init(kPi / kPolePairs); // theta_e = pi, the vector at 0
    mc_ctrl_align_t al{};
    const mc_ctrl_align_result_t r = run_align(b, al);
    ASSERT_EQ(r.status, MC_CTRL_ALIGN_DONE) << r.fail;
    EXPECT_NEAR(wrap_pi(r.offset_e_rad - true_offset(b)), 0.0, 0.01);
}

// Coulomb friction (10 % of the holding torque) holds the rotor short of
// the vector by the same angle from either side: the mean of the two
// approaches cancels it (a single approach would be off by asin(0.1) =
// 0.1 rad el.).
TEST(CtrlAlign, FrictionCancelsBetweenTheTwoApproaches)
{
    Bench b;
    b.rotor.coulomb_nm = 0.1 * 1.5 * kPolePairs * kFlux * 5.0;
    b.init(1.1);
    mc_ctrl_align_t al{};
    const mc_ctrl_align_result_t r = run_align(b, al);
    ASSERT_EQ(r.status, MC_CTRL_ALIGN_DONE) << r.fail;
    EXPECT_GT(std::fabs(r.hysteresis_e_rad), 0.05); // friction was there
    EXPECT_NEAR(wrap_pi(r.offset_e_rad - true_offset(b)), 0.0, 0.01);
}

// A load it can hold (a third of k i) biases the rotor by asin(1/3) = 0.34
// rad el.: halving the current moves it by about that much: refused,
// MC_CTRL_ALIGN_ERR_LOAD, and the drive faults (CONTROL) with the bridge
// open. A load it cannot hold (above k i): the rotor is dragged off the
// vector: SLIP, within 3/2 pi el. of travel.
TEST(CtrlAlign, RefusedUnderLoad)
{
    const double hold = 1.5 * kPolePairs * kFlux * 5.0;
    {
        Bench b;
        b.rotor.load_nm = hold / 3.0;
        // a heavier rotor, damped (0.7) by the damping current: it falls
        // towards the load while the current ramps up and settles on the
        // loaded side of the vector without slipping past it
        b.rotor_j = 1.0e-4;
        b.init(0.5);
        mc_ctrl_align_t al{};
        const double k = hold * kPolePairs;
        const mc_ctrl_align_result_t r = run_align(
            b, al, 60000, static_cast<float>(2.0 * 0.7 * std::sqrt(k * 1.0e-4) / (hold / 5.0)));
        ASSERT_EQ(r.status, MC_CTRL_ALIGN_FAILED);
        EXPECT_EQ(r.fail, MC_CTRL_ALIGN_ERR_LOAD);
        EXPECT_GT(std::fabs(r.load_shift_e_rad), 0.2); // asin(2/3) - asin(1/3) = 0.39
        EXPECT_NE(b.d.faults & MC_DRIVE_FAULT_CONTROL, 0u);
        EXPECT_FALSE(b.fake.pwm3.enabled);
    }
    {
        Bench b;
        b.rotor.load_nm = 1.5 * hold;
        b.init(0.5);
        mc_ctrl_align_t al{};
        const mc_ctrl_align_result_t r = run_align(b, al);
        ASSERT_EQ(r.status, MC_CTRL_ALIGN_FAILED);
        EXPECT_EQ(r.fail, MC_CTRL_ALIGN_ERR_SLIP);
        // bounded motion: 3/2 pi el. (the slip bound before the first rest)
        EXPECT_LE(r.travel_peak_m_rad, 1.5 * kPi / kPolePairs + 0.05);
        EXPECT_NE(b.d.faults & MC_DRIVE_FAULT_CONTROL, 0u);
    }
}

// A configuration that does not match the machine: the encoder wired the
// other way (the rotor seen moving against the vector's turn), or the
// wrong pole pairs (the sweep measures 4/5 of it):
// MC_CTRL_ALIGN_ERR_DIRECTION. A rotor held still (a jam) does not follow
// the vector's turn: SLIP.
TEST(CtrlAlign, WrongDirectionOrPolePairsIsNamed)
{
    {
        Bench b;
        b.reversed_wiring = true;
        b.init(0.8);
        mc_ctrl_align_t al{};
        const mc_ctrl_align_result_t r = run_align(b, al);
        ASSERT_EQ(r.status, MC_CTRL_ALIGN_FAILED);
        EXPECT_EQ(r.fail, MC_CTRL_ALIGN_ERR_DIRECTION);
    }
    {
        Bench b;
        b.rotor.pole_pairs = 5; // the motor has 5, the configuration says 4
        b.init(0.8);
        mc_ctrl_align_t al{};
        const mc_ctrl_align_result_t r = run_align(b, al);
        ASSERT_EQ(r.status, MC_CTRL_ALIGN_FAILED);
        EXPECT_EQ(r.fail, MC_CTRL_ALIGN_ERR_DIRECTION);
    }
    {
        Bench b;
        b.rotor.jammed = true;
        b.init(0.8);
        mc_ctrl_align_t al{};
        const mc_ctrl_align_result_t r = run_align(b, al);
        ASSERT_EQ(r.status, MC_CTRL_ALIGN_FAILED);
        EXPECT_EQ(r.fail, MC_CTRL_ALIGN_ERR_SLIP); // the vector turns, the rotor stays
    }
}

// A rotor without friction rings on the vector's spring: without the
// damping current it never settles (NOT_SETTLED at the first settle's
// timeout); with damping_a_s_rad for a damping ratio of 0.7 (2 z sqrt(k J)
// / k_t, k = k_t i p) it aligns as a damped one does (within the count's
// limit cycle: the same 0.01 rad el.).
TEST(CtrlAlign, DampingCurrentSettlesAFrictionlessRotor)
{
    const double kt = 1.5 * kPolePairs * kFlux;
    const double k = kt * 5.0 * kPolePairs; // N m per rad mech.
    for (const bool damped : {false, true}) {
        Bench b;
        b.rotor.b_nms = 0.0;
        b.init(0.9);
        mc_ctrl_align_t al{};
        mc_ctrl_align_cfg_t c = align_cfg(b.cfg);
        c.damping_a_s_rad = damped ? static_cast<float>(2.0 * 0.7 * std::sqrt(k * kJ) / kt) : 0.0f;
        c.t_timeout_s = 0.2f;
        ASSERT_EQ(mc_ctrl_align_init(&al, &c), MC_CTRL_ALIGN_ERR_NONE);
        ASSERT_EQ(0, mc_drive_attach_ctrl(&b.d, mc_ctrl_align_ops(&al)));
        ASSERT_EQ(0, mc_drive_set_mode(&b.d, MC_DRIVE_MODE_CTRL));
        mc_ctrl_align_result_t r{};
        int n = 0;
        for (; n < 60000 && r.status == MC_CTRL_ALIGN_RUNNING; ++n) {
            b.step(al.v);
            (void)mc_ctrl_align_get_result(&al, &r);
        }
        if (damped) {
            ASSERT_EQ(r.status, MC_CTRL_ALIGN_DONE) << r.fail;
            EXPECT_NEAR(wrap_pi(r.offset_e_rad - true_offset(b)), 0.0, 0.01);
        } else {
            ASSERT_EQ(r.status, MC_CTRL_ALIGN_FAILED);
            EXPECT_EQ(r.fail, MC_CTRL_ALIGN_ERR_NOT_SETTLED);
            // at the first settle's timeout: the ramp (0.05 s) and 0.2 s,
            // to a period
            EXPECT_NEAR(n * kDt, 0.25, 2.0 * kDt);
        }
    }
}

namespace
{

mc_ctrl_idx_cfg_t idx_cfg(const mc_drive_cfg_t &dc, const mc_hal_encoder_t *enc)
{
    mc_ctrl_idx_cfg_t c{};
    c.foc = dc.foc;
    c.pole_pairs = kPolePairs;
    c.i_max_a = dc.i_max_a;
    c.i_search_a = 5.0f;
    c.t_ramp_s = 0.05f;
    c.omega_search_e_rad_s = 40.0f; // 10 rad/s mechanical
    c.travel_max_m_rad = static_cast<float>(1.1 * 2.0 * kPi);
    c.first_direction = 1;
    c.p_enc = enc;
    return c;
}

mc_ctrl_idx_result_t run_idx(Bench &b, mc_ctrl_idx_t &ix, const mc_ctrl_idx_cfg_t &c,
                             int n_max = 200000)
{
    EXPECT_EQ(mc_ctrl_idx_init(&ix, &c), MC_CTRL_ALIGN_ERR_NONE);
    EXPECT_EQ(0, mc_drive_attach_ctrl(&b.d, mc_ctrl_idx_ops(&ix)));
    EXPECT_EQ(0, mc_drive_set_mode(&b.d, MC_DRIVE_MODE_CTRL));
    mc_ctrl_idx_result_t r{};
    for (int n = 0; n < n_max; ++n) {
        b.step(ix.v);
        (void)mc_ctrl_idx_get_result(&ix, &r);
        if (r.status != MC_CTRL_ALIGN_RUNNING) {
            break;
        }
    }
    return r;
}

} // namespace

TEST(CtrlIdx, InitRefusesOutOfRange)
{
    Bench b;
    b.init(0.0);
    mc_ctrl_idx_t ix{};
    const mc_ctrl_idx_cfg_t good = idx_cfg(b.cfg, &b.fake.encoder_dev);
    ASSERT_EQ(mc_ctrl_idx_init(&ix, &good), MC_CTRL_ALIGN_ERR_NONE);
    mc_ctrl_idx_cfg_t c = good;
    c.i_search_a = 21.0f;
    EXPECT_EQ(mc_ctrl_idx_init(&ix, &c), MC_CTRL_ALIGN_ERR_CFG);
    c = good;
    c.travel_max_m_rad = 1.0f; // less than a turn: an index may be missed
    EXPECT_EQ(mc_ctrl_idx_init(&ix, &c), MC_CTRL_ALIGN_ERR_CFG);
    c = good;
    c.first_direction = 0;
    EXPECT_EQ(mc_ctrl_idx_init(&ix, &c), MC_CTRL_ALIGN_ERR_CFG);
    c = good;
    c.p_enc = nullptr;
    EXPECT_EQ(mc_ctrl_idx_init(&ix, &c), MC_CTRL_ALIGN_ERR_CFG);
    c = good;
    c.omega_search_e_rad_s = 5000.0f;
    EXPECT_EQ(mc_ctrl_idx_init(&ix, &c), MC_CTRL_ALIGN_ERR_CFG);
}

// Found going forward: the rotor follows the vector to the mark; the
// search stops there (the current released), the travel under one turn.
TEST(CtrlIdx, FoundInTheFirstDirection)
{
    Bench b;
    b.has_index = true;
    b.index_at = 2.0;
    b.init(0.3);
    mc_ctrl_idx_t ix{};
    const mc_ctrl_idx_result_t r = run_idx(b, ix, idx_cfg(b.cfg, &b.fake.encoder_dev));
    ASSERT_EQ(r.status, MC_CTRL_ALIGN_DONE) << r.fail;
    EXPECT_EQ(r.direction, 1);
    EXPECT_TRUE(b.index_seen);
    // the mark 1.7 rad ahead; the rotor may first snap up to pi / p back
    EXPECT_NEAR(r.travel_at_index_m_rad, 1.7, kPi / kPolePairs + 0.01);
    EXPECT_LE(r.travel_peak_m_rad, 2.0 * kPi);
    EXPECT_EQ(b.d.faults, 0u);
    EXPECT_EQ(ix.v.i_cmd_a, 0.0f);
}

// An end stop ahead of the rotor (the mark behind it): the rotor stops
// following, the search turns back and finds the mark the other way.
TEST(CtrlIdx, EndStopTurnsTheSearchBack)
{
    Bench b;
    b.has_index = true;
    b.index_at = -1.0;
    b.rotor.stop_hi = 1.5; // forward blocked 1.2 rad ahead
    b.init(0.3);
    mc_ctrl_idx_t ix{};
    const mc_ctrl_idx_result_t r = run_idx(b, ix, idx_cfg(b.cfg, &b.fake.encoder_dev));
    ASSERT_EQ(r.status, MC_CTRL_ALIGN_DONE) << r.fail;
    EXPECT_EQ(r.direction, -1);
    EXPECT_LE(b.rotor.th, 1.5);
}

// No index on the encoder: the search goes travel_max each way and fails
// by name; the motion stays within the bound (plus the snap of the first
// ramp and one period).
TEST(CtrlIdx, NotFoundAfterBothDirections)
{
    Bench b;
    b.init(0.3);
    mc_ctrl_idx_t ix{};
    const mc_ctrl_idx_cfg_t c = idx_cfg(b.cfg, &b.fake.encoder_dev);
    const mc_ctrl_idx_result_t r = run_idx(b, ix, c);
    ASSERT_EQ(r.status, MC_CTRL_ALIGN_FAILED);
    EXPECT_EQ(r.fail, MC_CTRL_ALIGN_ERR_NOT_FOUND);
    // the rotor coasts a little past the limit when the vector turns back
    // (at 10 rad/s, with the vector's spring: 0.012 rad here): 0.05 rad
    EXPECT_LE(r.travel_peak_m_rad, c.travel_max_m_rad + 0.05);
    EXPECT_GE(r.travel_peak_m_rad, c.travel_max_m_rad - 0.01);
    EXPECT_NE(b.d.faults & MC_DRIVE_FAULT_CONTROL, 0u);
    EXPECT_FALSE(b.fake.pwm3.enabled);
}

// A rotor that cannot move either way: NO_MOTION (after turning back once).
TEST(CtrlIdx, JammedRotorIsNoMotion)
{
    Bench b;
    b.has_index = true;
    b.index_at = 2.0;
    b.rotor.jammed = true;
    b.init(0.3);
    mc_ctrl_idx_t ix{};
    const mc_ctrl_idx_result_t r = run_idx(b, ix, idx_cfg(b.cfg, &b.fake.encoder_dev));
    ASSERT_EQ(r.status, MC_CTRL_ALIGN_FAILED);
    EXPECT_EQ(r.fail, MC_CTRL_ALIGN_ERR_NO_MOTION);
}

// The encoder capability failing its read (the plug-in's own read, for
// the index flag): MC_CTRL_ALIGN_ERR_ENCODER at once, duties for zero
// current. Called without the drive (its fast op on a measurement).
TEST(CtrlIdx, EncoderReadErrorIsNamed)
{
    Bench b;
    b.init(0.3);
    mc_ctrl_idx_t ix{};
    const mc_ctrl_idx_cfg_t c = idx_cfg(b.cfg, &b.fake.encoder_dev);
    ASSERT_EQ(mc_ctrl_idx_init(&ix, &c), MC_CTRL_ALIGN_ERR_NONE);
    mc_drive_meas_t m{};
    m.vbus_v = kVbus;
    m.have_encoder = true;
    m.theta_m_rad = 0.3f;
    m.enc_cpr = kCpr;
    m.dt_s = kDt;
    mc_drive_out_t out{};
    ASSERT_EQ(mc_ctrl_idx_fast(&ix, &m, &out), MC_CTRL_ALIGN_ERR_NONE);
    ASSERT_EQ(0, mc_hal_fake_inject_error(&b.fake, MC_HAL_FAKE_ENCODER_READ, -EIO, 1));
    EXPECT_EQ(mc_ctrl_idx_fast(&ix, &m, &out), MC_CTRL_ALIGN_ERR_ENCODER);
    mc_ctrl_idx_result_t r{};
    ASSERT_EQ(mc_ctrl_idx_get_result(&ix, &r), MC_CTRL_ALIGN_ERR_NONE);
    EXPECT_EQ(r.status, MC_CTRL_ALIGN_FAILED);
    EXPECT_EQ(r.fail, MC_CTRL_ALIGN_ERR_ENCODER);
    // sticky: the next steps return it too
    EXPECT_EQ(mc_ctrl_idx_fast(&ix, &m, &out), MC_CTRL_ALIGN_ERR_ENCODER);
    m.have_encoder = false; // and a measurement without the encoder: MEAS
    mc_ctrl_align_t al{};
    const mc_ctrl_align_cfg_t ac = align_cfg(b.cfg);
    ASSERT_EQ(mc_ctrl_align_init(&al, &ac), MC_CTRL_ALIGN_ERR_NONE);
    EXPECT_EQ(mc_ctrl_align_fast(&al, &m, &out), MC_CTRL_ALIGN_ERR_MEAS);
    EXPECT_EQ(mc_ctrl_align_fast(nullptr, &m, &out), MC_CTRL_ALIGN_ERR_NULL);
}

// Bounded current: the vector never exceeds its configured magnitude, and
// with a damping gain high enough to ask for more than the drive's limit
// (a frictionless rotor ringing at the first snap), the damping current is
// cut so that |i| <= i_max_a. Tolerance: float rounding of sqrt(i_max^2 -
// i^2) (1e-4 A).
TEST(CtrlAlign, CurrentStaysWithinItsBounds)
{
    {
        Bench b;
        b.init(2.2);
        mc_ctrl_align_t al{};
        const mc_ctrl_align_result_t r = run_align(b, al);
        ASSERT_EQ(r.status, MC_CTRL_ALIGN_DONE) << r.fail;
        EXPECT_LE(b.i_peak, 5.0 + 1e-4); // i_align_a, no damping: iq = 0
        EXPECT_GE(b.i_peak, 5.0 - 1e-4); // and it did reach it
        EXPECT_EQ(b.iq_peak, 0.0);
    }
    {
        Bench b;
        b.rotor.b_nms = 0.0;
        b.init(2.2);
        mc_ctrl_align_t al{};
        // 50 A s/rad: at the snap's ~30 rad/s it asks for ~1500 A of iq
        const mc_ctrl_align_result_t r = run_align(b, al, 60000, 50.0f);
        (void)r; // the outcome is not the point: the bound is
        const double i_max = b.cfg.i_max_a;
        EXPECT_GT(b.iq_peak, 1.0);         // the damping current was there
        EXPECT_LE(b.i_peak, i_max + 1e-4); // and cut at the drive's limit
        EXPECT_LT(b.iq_peak, i_max + 1e-4);
    }
}

// The index search's current: the vector's magnitude is i_search_a (no
// damping configured), the damping current at most the rest of i_max_a.
TEST(CtrlIdx, CurrentStaysWithinItsBounds)
{
    for (const float damping : {0.0f, 50.0f}) {
        Bench b;
        b.has_index = true;
        b.index_at = 2.0;
        b.init(0.3);
        mc_ctrl_idx_t ix{};
        mc_ctrl_idx_cfg_t c = idx_cfg(b.cfg, &b.fake.encoder_dev);
        c.damping_a_s_rad = damping;
        const mc_ctrl_idx_result_t r = run_idx(b, ix, c);
        ASSERT_EQ(r.status, MC_CTRL_ALIGN_DONE) << r.fail;
        if (damping == 0.0f) {
            EXPECT_NEAR(b.i_peak, 5.0, 1e-4);
        } else {
            EXPECT_GT(b.iq_peak, 1.0);
            EXPECT_LE(b.i_peak, static_cast<double>(b.cfg.i_max_a) + 1e-4);
        }
    }
}

// Both directions: first_direction = -1 searches backwards first (the mark
// behind the rotor is found without a forward move beyond the first
// snap); a mark ahead is found after the backward leg ends at travel_max,
// turned forward. Travel never beyond travel_max (+ the coast, 0.05 rad as
// in NotFoundAfterBothDirections) either way.
TEST(CtrlIdx, SearchesBothDirections)
{
    {
        Bench b;
        b.has_index = true;
        b.index_at = -1.0; // 1.3 rad behind
        b.init(0.3);
        mc_ctrl_idx_t ix{};
        mc_ctrl_idx_cfg_t c = idx_cfg(b.cfg, &b.fake.encoder_dev);
        c.first_direction = -1;
        const mc_ctrl_idx_result_t r = run_idx(b, ix, c);
        ASSERT_EQ(r.status, MC_CTRL_ALIGN_DONE) << r.fail;
        EXPECT_EQ(r.direction, -1);
        EXPECT_NEAR(r.travel_at_index_m_rad, -1.3, kPi / kPolePairs + 0.01);
        EXPECT_LE(b.th_hi, kPi / kPolePairs + 0.01); // no forward leg
    }
    {
        Bench b;
        b.has_index = true;
        // 1.3 rad ahead, 2 pi - 1.3 = 4.98 rad behind: within one leg's
        // travel forward, beyond it backward
        b.index_at = 1.6;
        b.init(0.3);
        mc_ctrl_idx_t ix{};
        mc_ctrl_idx_cfg_t c = idx_cfg(b.cfg, &b.fake.encoder_dev);
        c.first_direction = -1;
        c.travel_max_m_rad = static_cast<float>(2.0 * kPi / kPolePairs * 1.5); // 2.36 rad
        const mc_ctrl_idx_result_t r = run_idx(b, ix, c);
        ASSERT_EQ(r.status, MC_CTRL_ALIGN_DONE) << r.fail;
        EXPECT_EQ(r.direction, 1);
        EXPECT_LE(-b.th_lo, c.travel_max_m_rad + 0.05); // the backward leg's bound
        EXPECT_GE(-b.th_lo, c.travel_max_m_rad - 0.01); // and it went all of it
    }
    {
        Bench b; // no mark: the bound holds both ways
        b.init(0.3);
        mc_ctrl_idx_t ix{};
        const mc_ctrl_idx_cfg_t c = idx_cfg(b.cfg, &b.fake.encoder_dev);
        const mc_ctrl_idx_result_t r = run_idx(b, ix, c);
        ASSERT_EQ(r.fail, MC_CTRL_ALIGN_ERR_NOT_FOUND);
        EXPECT_NEAR(b.th_hi, c.travel_max_m_rad, 0.05);
        EXPECT_NEAR(-b.th_lo, c.travel_max_m_rad, 0.05);
    }
}

// The drive's angle reference with the plug-ins (mc_drive.h): an ALIGN
// drive refuses CURRENT after power-up (NEED_ALIGN), runs the alignment
// (it finds the angle), takes its offset and then runs CURRENT with it; an
// INDEX drive refuses until the search has found the mark, with the
// encoder-jump check on (the count's jump at the index is not a fault).
TEST(CtrlAngleRef, AlignmentThenSensored)
{
    Bench b;
    b.cfg.angle_ref = MC_DRIVE_ANGLE_REF_ALIGN;
    b.init(1.9);
    EXPECT_EQ(mc_drive_angle_state(&b.d), MC_DRIVE_ANGLE_NEED_ALIGN);
    EXPECT_EQ(-EACCES, mc_drive_set_mode(&b.d, MC_DRIVE_MODE_CURRENT));
    mc_ctrl_align_t al{};
    const mc_ctrl_align_result_t r = run_align(b, al);
    ASSERT_EQ(r.status, MC_CTRL_ALIGN_DONE) << r.fail;
    ASSERT_EQ(0, mc_drive_set_mode(&b.d, MC_DRIVE_MODE_IDLE));
    ASSERT_EQ(0, mc_drive_set_encoder_offset(&b.d, r.offset_e_rad));
    EXPECT_EQ(mc_drive_angle_state(&b.d), MC_DRIVE_ANGLE_KNOWN);
    ASSERT_EQ(0, mc_drive_set_mode(&b.d, MC_DRIVE_MODE_CURRENT));
    b.step(al.v);
    // the drive's angle is the rotor's: 0.01 rad el. as OffsetAtAnyPowerUpAngle
    EXPECT_NEAR(wrap_pi(b.d.tm.theta_e_rad - kPolePairs * b.rotor.th), 0.0, 0.01);
}

TEST(CtrlAngleRef, IndexSearchThenSensored)
{
    Bench b;
    b.cfg.angle_ref = MC_DRIVE_ANGLE_REF_INDEX;
    b.cfg.omega_max_rad_s = 200.0f; // the jump check on
    b.has_index = true;
    b.index_at = 2.0;
    b.init(0.3);
    EXPECT_EQ(mc_drive_angle_state(&b.d), MC_DRIVE_ANGLE_NEED_INDEX);
    EXPECT_EQ(-EACCES, mc_drive_set_mode(&b.d, MC_DRIVE_MODE_CURRENT));
    mc_ctrl_idx_t ix{};
    const mc_ctrl_idx_result_t r = run_idx(b, ix, idx_cfg(b.cfg, &b.fake.encoder_dev));
    ASSERT_EQ(r.status, MC_CTRL_ALIGN_DONE) << r.fail;
    EXPECT_EQ(b.d.faults, 0u);
    EXPECT_EQ(mc_drive_angle_state(&b.d), MC_DRIVE_ANGLE_KNOWN);
    ASSERT_EQ(0, mc_drive_set_mode(&b.d, MC_DRIVE_MODE_IDLE));
    EXPECT_EQ(0, mc_drive_set_mode(&b.d, MC_DRIVE_MODE_CURRENT));
}
