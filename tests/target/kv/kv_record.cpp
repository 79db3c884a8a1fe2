// Records the input vectors of the kernel families (kv.h) into a directory,
// one <family>.in per family:
//   foc         the FOC inputs the drive handed its current controller in
//               SIL runs of the foc-current-step scenario (FocSil, 0.03 s
//               at 20 kHz, without and with current-sensor noise), then
//               random operating points and the error cases (NaN current,
//               infinite angle, vbus <= 0) followed by normal records again;
//   observer, filters, pi2d, csmc
//               smooth trajectories of the kernel's plant (computed here in
//               double: a PMSM turning at a varying speed, a position ramp
//               and sinusoid, a speed profile with its derivatives, the
//               stepper's error signals), then random operating points,
//               non-finite inputs, a reset record and the trajectory again;
//   the others  edge values (0, -0, +-pi, huge, denormal, NaN, inf; q31
//               extremes) and uniformly drawn operating points (fixed-seed
//               std::mt19937, the same file on every run).
// usage: kv_record <dir>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "foc_sil.hpp"

namespace
{

using Words = std::vector<uint32_t>;

uint32_t fw(float v)
{
    uint32_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
}
uint32_t qw(int32_t v)
{
    return static_cast<uint32_t>(v);
}

class Rng
{
  public:
    explicit Rng(uint32_t seed) : g_(seed)
    {
    }
    float f(float lo, float hi)
    {
        return std::uniform_real_distribution<float>(lo, hi)(g_);
    }
    int32_t q()
    {
        return static_cast<int32_t>(g_());
    }

  private:
    std::mt19937 g_;
};

const float kNan = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();
const std::vector<float> kEdgesF = {0.0f,     -0.0f,     3.14159265f, -3.14159265f, 1.5707963f,
                                    1.0e-40f, -1.0e-40f, 1.0e6f,      -3.0e9f,      1.0e30f,
                                    kNan,     kInf,      -kInf,       1.0f,         -1.0f};
const std::vector<int32_t> kEdgesQ = {
    0, 1, -1, INT32_MAX, INT32_MIN, INT32_MIN + 1, 0x40000000, -0x40000000, 0x20000000, 12345};

Words math_f32()
{
    Words w;
    for (float x : kEdgesF)
        for (float y : kEdgesF)
            w.insert(w.end(), {fw(x), fw(y)});
    Rng r(1);
    for (int i = 0; i < 4000; ++i) {
        const float x = r.f(-100.0f, 100.0f);
        const float y = r.f(-10.0f, 10.0f);
        w.insert(w.end(), {fw(x), fw(y)});
    }
    return w;
}

Words math_q31()
{
    Words w;
    for (int32_t a : kEdgesQ)
        for (int32_t b : kEdgesQ)
            w.insert(w.end(), {qw(a), qw(b), fw(0.5f)});
    for (float x : kEdgesF)
        w.insert(w.end(), {qw(0), qw(1), fw(x)});
    Rng r(2);
    for (int i = 0; i < 4000; ++i) {
        const int32_t a = r.q();
        const int32_t b = r.q();
        w.insert(w.end(), {qw(a), qw(b), fw(r.f(-1.5f, 1.5f))});
    }
    return w;
}

Words transforms()
{
    Words w;
    for (float x : kEdgesF) {
        w.insert(w.end(), {fw(x), fw(1.0f), fw(-1.0f), fw(x), qw(INT32_MAX), qw(INT32_MIN), qw(0),
                           qw(INT32_MIN)});
    }
    Rng r(3);
    for (int i = 0; i < 4000; ++i) {
        const float ia = r.f(-50.0f, 50.0f), ib = r.f(-50.0f, 50.0f), ic = r.f(-50.0f, 50.0f);
        const float th = r.f(-4.0f, 4.0f);
        const int32_t qa = r.q(), qb = r.q(), qc = r.q(), qt = r.q();
        w.insert(w.end(), {fw(ia), fw(ib), fw(ic), fw(th), qw(qa), qw(qb), qw(qc), qw(qt)});
    }
    return w;
}

Words svpwm()
{
    Words w;
    for (float v : kEdgesF) {
        w.insert(w.end(),
                 {fw(v), fw(10.0f), fw(24.0f), qw(INT32_MAX), qw(INT32_MIN), qw(0x40000000)});
        w.insert(w.end(), {fw(10.0f), fw(5.0f), fw(v), qw(1000), qw(-1000), qw(0)});
    }
    Rng r(4);
    for (int i = 0; i < 4000; ++i) {
        const float va = r.f(-300.0f, 300.0f), vb = r.f(-300.0f, 300.0f), vbus = r.f(10.0f, 400.0f);
        const int32_t qa = r.q(), qb = r.q();
        const int32_t qbus = static_cast<int32_t>(static_cast<uint32_t>(r.q()) >> 1);
        w.insert(w.end(), {fw(va), fw(vb), fw(vbus), qw(qa), qw(qb), qw(qbus)});
    }
    return w;
}

Words pi()
{
    Words w;
    Rng r(5);
    for (int i = 0; i < 4000; ++i) {
        float lo = r.f(-15.0f, 0.0f), hi = r.f(0.0f, 15.0f);
        float e = r.f(-8.0f, 8.0f);
        if (i % 500 == 250)
            std::swap(lo, hi); // refused dynamic limits
        if (i % 1000 == 700)
            e = kNan; // refused error
        w.insert(w.end(), {fw(e), fw(r.f(-2.0f, 2.0f)), fw(lo), fw(hi), qw(r.q()), qw(r.q() >> 2)});
    }
    return w;
}

void foc_record(Words &w, float ia, float ib, float ic, bool three, float th, float om, float vbus,
                float idr, float iqr)
{
    w.insert(w.end(),
             {fw(ia), fw(ib), fw(ic), three ? 1u : 0u, fw(th), fw(om), fw(vbus), fw(idr), fw(iqr)});
}

// The FOC inputs of one SIL run of foc-current-step, as the drive formed them.
void foc_from_sil(Words &w, double noise_rms_a)
{
    mcsim::FocSilOptions o;
    o.bw_rad_s = 2.0 * 3.14159265358979323846 * 200.0;
    o.J_kgm2 = 0.1;
    o.noise_rms_a = noise_rms_a;
    mcsim::FocSil sil(o);
    mc_drive_t &d = sil.drive();
    (void)mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT);
    const long n = std::lround(0.03 * o.pwm_hz);
    for (long k = 0; k < n; ++k) {
        const double t = sil.board().t_s();
        (void)mc_drive_set_current_ref(&d, (t >= 0.015) ? -1.0f : 0.0f, (t >= 0.002) ? 2.0f : 0.0f);
        sil.step();
        const mc_drive_telemetry_t &tm = d.tm;
        const float omega_e = tm.omega_m_rad_s * static_cast<float>(d.cfg.pole_pairs);
        foc_record(w, tm.ia_a, tm.ib_a, tm.ic_a, false, tm.theta_e_rad, omega_e, tm.vbus_v,
                   tm.id_ref_a, tm.iq_ref_a);
    }
}

Words foc()
{
    Words w;
    foc_from_sil(w, 0.0);
    foc_from_sil(w, 0.05);
    Rng r(6);
    for (int i = 0; i < 400; ++i) {
        foc_record(w, r.f(-5.0f, 5.0f), r.f(-5.0f, 5.0f), r.f(-5.0f, 5.0f), (i & 1) != 0,
                   r.f(-7.0f, 7.0f), r.f(-1500.0f, 1500.0f), r.f(150.0f, 210.0f), r.f(-3.0f, 0.0f),
                   r.f(-8.0f, 8.0f));
    }
    foc_record(w, kNan, 0.0f, 0.0f, false, 0.0f, 0.0f, 200.0f, 0.0f, 1.0f);
    foc_record(w, 1.0f, 0.0f, 0.0f, false, kInf, 0.0f, 200.0f, 0.0f, 1.0f);
    foc_record(w, 1.0f, 0.0f, 0.0f, false, 0.0f, 0.0f, 0.0f, 0.0f, 1.0f);
    foc_record(w, 1.0f, 0.0f, 0.0f, false, 0.0f, 0.0f, -5.0f, 0.0f, 1.0f);
    for (int i = 0; i < 20; ++i) {
        foc_record(w, 1.0f, -0.5f, -0.5f, false, 0.1f * i, 100.0f, 200.0f, 0.0f, 1.0f);
    }
    return w;
}

// Flux observer, PLL and I&I observer: the paper-002 motor (R, L, flux of
// kv_families.c, 4 pole pairs) at 20 kHz turning with a speed that ramps
// from 0 to 600 rad/s electrical and back, iq = 2 A (alpha-beta currents and
// the voltage that produces them: v = R i + L di/dt + omega flux (-sin, cos)),
// shaft angle theta_e / 4, torque 0.66 iq.
void observer_traj(Words &w, Rng &r, int n, double th0, double noise_a)
{
    const double R = 0.675, L = 1.14e-3, psi = 0.11, dt = 5.0e-5;
    double th = th0;
    for (int k = 0; k < n; ++k) {
        const double t = k * dt;
        const double om = 600.0 * std::sin(3.14159265358979 * t / (n * dt));
        const double iq = 2.0;
        const double ia = -iq * std::sin(th), ib = iq * std::cos(th);
        const double dia = -iq * std::cos(th) * om, dib = -iq * std::sin(th) * om;
        const double va = R * ia + L * dia - om * psi * std::sin(th);
        const double vb = R * ib + L * dib + om * psi * std::cos(th);
        const double na = noise_a * r.f(-1.0f, 1.0f), nb = noise_a * r.f(-1.0f, 1.0f);
        w.insert(w.end(), {fw(static_cast<float>(va)), fw(static_cast<float>(vb)),
                           fw(static_cast<float>(ia + na)), fw(static_cast<float>(ib + nb)),
                           fw(static_cast<float>(th / 4.0)), fw(static_cast<float>(0.66 * iq)), 0u,
                           fw(0.0f), fw(0.0f)});
        th += om * dt;
    }
}

Words observer()
{
    Words w;
    Rng r(7);
    observer_traj(w, r, 3000, 0.3, 0.0);
    observer_traj(w, r, 1000, 1.0, 0.05);
    for (int i = 0; i < 1000; ++i) {
        w.insert(w.end(),
                 {fw(r.f(-30.0f, 30.0f)), fw(r.f(-30.0f, 30.0f)), fw(r.f(-5.0f, 5.0f)),
                  fw(r.f(-5.0f, 5.0f)), fw(r.f(-100.0f, 100.0f)), fw(r.f(-1.0f, 1.0f)),
                  (i % 250 == 0) ? 1u : 0u, fw(r.f(-4.0f, 4.0f)), fw(r.f(-800.0f, 800.0f))});
    }
    for (float x : kEdgesF) {
        w.insert(w.end(),
                 {fw(x), fw(1.0f), fw(0.5f), fw(-0.5f), fw(x), fw(0.1f), 0u, fw(0.0f), fw(0.0f)});
        w.insert(w.end(),
                 {fw(1.0f), fw(1.0f), fw(x), fw(0.5f), fw(0.2f), fw(x), 0u, fw(0.0f), fw(0.0f)});
    }
    // a refused reset (NaN guess), then a good one and the trajectory again
    w.insert(w.end(),
             {fw(0.0f), fw(0.0f), fw(0.0f), fw(0.0f), fw(0.0f), fw(0.0f), 1u, fw(kNan), fw(0.0f)});
    w.insert(w.end(),
             {fw(0.0f), fw(0.0f), fw(0.0f), fw(2.0f), fw(0.0f), fw(1.32f), 1u, fw(0.0f), fw(0.0f)});
    observer_traj(w, r, 2000, 0.0, 0.0);
    return w;
}

// Dirty derivative: a ramp (exactly differentiated), a sinusoid, steps,
// random values, resets and non-finite inputs.
Words filters()
{
    Words w;
    for (int k = 0; k < 1000; ++k)
        w.insert(w.end(), {fw(0.003f * static_cast<float>(k)), 0u, 0u});
    for (int k = 0; k < 2000; ++k) {
        const float y =
            static_cast<float>(0.5 * std::sin(2.0 * 3.14159265358979 * 3.0 * k * 1.0e-4));
        w.insert(w.end(), {fw(y), 0u, 0u});
    }
    Rng r(8);
    for (int i = 0; i < 2000; ++i) {
        const bool rst = (i % 400 == 0);
        w.insert(w.end(), {fw((i % 100 < 50) ? 1.0f : r.f(-2.0f, 2.0f)), rst ? 1u : 0u,
                           fw(r.f(-1.0f, 1.0f))});
    }
    for (float x : kEdgesF) {
        w.insert(w.end(), {fw(x), 0u, 0u});
        w.insert(w.end(), {fw(0.25f), 1u, fw(x)});
        w.insert(w.end(), {fw(0.5f), 0u, 0u});
    }
    return w;
}

void pi2d_record(Words &w, float id, float iq, float th, float thr, float om, float al, float jerk,
                 float idr, float didr, uint32_t cmd, float q0, float nu0)
{
    w.insert(w.end(), {fw(id), fw(iq), fw(th), fw(thr), fw(om), fw(al), fw(jerk), fw(idr), fw(didr),
                       cmd, fw(q0), fw(nu0)});
}

// PI2D: a speed reference omega = 100 (1 - cos(2 pi t / T)) / 2 with its
// derivatives, the position lagging the integrated reference by a decaying
// oscillation, currents near what the law asks; then random points (where
// the motor law's limits act), non-finite inputs, resets.
Words pi2d()
{
    Words w;
    const double dt = 5.0e-5, T = 0.2, pi = 3.14159265358979;
    double thr = 0.0;
    for (int k = 0; k < 4000; ++k) {
        const double t = k * dt, a = 2.0 * pi / T;
        const double om = 50.0 * (1.0 - std::cos(a * t)), al = 50.0 * a * std::sin(a * t);
        const double jerk = 50.0 * a * a * std::cos(a * t);
        const double e = 0.02 * std::exp(-t / 0.05) * std::sin(2.0 * pi * 20.0 * t);
        pi2d_record(w, static_cast<float>(0.05 * std::sin(7.0 * t)),
                    static_cast<float>(0.5 + 0.2 * std::sin(a * t)), static_cast<float>(thr + e),
                    static_cast<float>(thr), static_cast<float>(om), static_cast<float>(al),
                    static_cast<float>(jerk), 0.0f, 0.0f, 0u, 0.0f, 0.0f);
        thr += om * dt;
    }
    Rng r(9);
    for (int i = 0; i < 1500; ++i) {
        const float thr_i = r.f(-10.0f, 10.0f);
        pi2d_record(w, r.f(-6.0f, 6.0f), r.f(-6.0f, 6.0f), thr_i + r.f(-0.5f, 0.5f), thr_i,
                    r.f(-300.0f, 300.0f), r.f(-1000.0f, 1000.0f), r.f(-1e4f, 1e4f),
                    r.f(-1.0f, 0.0f), r.f(-10.0f, 10.0f), (i % 300 == 150) ? 1u : 0u,
                    r.f(-0.5f, 0.5f), r.f(-2.0f, 2.0f));
    }
    for (float x : kEdgesF) {
        pi2d_record(w, x, 0.5f, 0.01f, 0.0f, 10.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0u, 0.0f, 0.0f);
        pi2d_record(w, 0.1f, 0.5f, x, 0.0f, 10.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0u, 0.0f, 0.0f);
        pi2d_record(w, 0.1f, 0.5f, 0.01f, 0.0f, 10.0f, 0.0f, 0.0f, 0.0f, 0.0f, 1u, x, 0.1f);
    }
    return w;
}

void csmc_record(Words &w, float e1, float e2, float de2, float dde2, float id, float iq, float om,
                 float didd, float dddphi, uint32_t cmd)
{
    w.insert(w.end(), {fw(e1), fw(e2), fw(de2), fw(dde2), fw(id), fw(iq), fw(om), fw(didd),
                       fw(dddphi), cmd});
}

// CSMC: at 100 kHz, a position error decaying as a damped sinusoid (with
// its exact derivatives) while the rotor follows phi_d = 0.5 cos(2 pi t),
// currents around the load's; then random errors (inside and outside the
// boundary layers), non-finite inputs and resets.
Words csmc()
{
    Words w;
    const double dt = 1.0e-5, pi = 3.14159265358979;
    for (int k = 0; k < 5000; ++k) {
        const double t = k * dt, s = 60.0, wd = 2.0 * pi * 25.0;
        const double ex = std::exp(-s * t), c = std::cos(wd * t), sn = std::sin(wd * t);
        const double e2 = 0.02 * ex * c;
        const double de2 = 0.02 * ex * (-s * c - wd * sn);
        const double dde2 = 0.02 * ex * ((s * s - wd * wd) * c + 2.0 * s * wd * sn);
        const double om = -pi * std::sin(2.0 * pi * t) + de2;
        csmc_record(w, static_cast<float>(0.1 * ex * sn), static_cast<float>(e2),
                    static_cast<float>(de2), static_cast<float>(dde2),
                    static_cast<float>(0.1 + 0.1 * ex * sn), static_cast<float>(1.5 + 0.5 * sn),
                    static_cast<float>(om), 0.0f,
                    static_cast<float>(0.5 * 8.0 * pi * pi * pi * std::sin(2.0 * pi * t)), 0u);
    }
    Rng r(10);
    for (int i = 0; i < 1500; ++i) {
        const float sc = (i % 2 == 0) ? 0.01f : 1.0f; // inside / outside the layers
        csmc_record(w, sc * r.f(-1.0f, 1.0f), sc * r.f(-0.05f, 0.05f), sc * r.f(-5.0f, 5.0f),
                    sc * r.f(-500.0f, 500.0f), r.f(-2.0f, 2.0f), r.f(-2.0f, 2.0f),
                    r.f(-20.0f, 20.0f), r.f(-1.0f, 1.0f), r.f(-100.0f, 100.0f),
                    (i % 500 == 250) ? 1u : 0u);
    }
    for (float x : kEdgesF) {
        csmc_record(w, x, 0.001f, 0.0f, 0.0f, 0.1f, 1.0f, 1.0f, 0.0f, 0.0f, 0u);
        csmc_record(w, 0.01f, x, 0.0f, 0.0f, 0.1f, 1.0f, 1.0f, 0.0f, 0.0f, 0u);
        csmc_record(w, 0.01f, 0.001f, 0.0f, 0.0f, 0.1f, 1.0f, x, 0.0f, 0.0f, 0u);
        csmc_record(w, 0.01f, 0.001f, x, 0.0f, 0.1f, 1.0f, 1.0f, 0.0f, 0.0f, 1u);
    }
    return w;
}

bool write(const std::string &dir, const char *family, const Words &w)
{
    const std::string path = dir + "/" + family + ".in";
    std::FILE *f = std::fopen(path.c_str(), "wb");
    if (f == nullptr)
        return false;
    // Little-endian words: the host is x86-64, the target reads them as they are.
    const bool ok = std::fwrite(w.data(), sizeof(uint32_t), w.size(), f) == w.size();
    return (std::fclose(f) == 0) && ok;
}

} // namespace

int main(int argc, char **argv)
{
    if (argc != 2) {
        std::fprintf(stderr, "usage: kv_record <dir>\n");
        return 2;
    }
    const std::string dir = argv[1];
    const bool ok = write(dir, "math_f32", math_f32()) && write(dir, "math_q31", math_q31()) &&
                    write(dir, "transforms", transforms()) && write(dir, "svpwm", svpwm()) &&
                    write(dir, "pi", pi()) && write(dir, "foc", foc()) &&
                    write(dir, "observer", observer()) && write(dir, "filters", filters()) &&
                    write(dir, "pi2d", pi2d()) && write(dir, "csmc", csmc());
    if (!ok) {
        std::fprintf(stderr, "kv_record: cannot write into %s\n", dir.c_str());
        return 1;
    }
    return 0;
}
