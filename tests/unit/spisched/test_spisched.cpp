// The SPI bus schedule against a simulated fast loop: a DRV8301 model (the
// slow side's device, set up and supervised through the schedule's
// handle) and an encoder device on one bus; the fast loop (run inside the
// slow side's wait, as the ADC interrupt preempts PendSV on the MCU) makes
// its encoder frame and then the schedule's slot each PWM period.
#include <gtest/gtest.h>

#include <vector>

#include "drv8301_model.h"
#include "mc_drv8301.h"
#include "mc_spisched.h"

namespace
{

constexpr uint32_t kTickHz = 1000000u; // 1 us per tick
constexpr uint32_t kPeriodTicks = 50u; // 20 kHz PWM
constexpr uint32_t kSlowDivider = 20u; // the 1 kHz slow loop

// One SPI bus: whoever starts a frame while another is on it fails the
// test; every frame is logged with its device and its context.
struct Bus {
    Drv8301Model drv;
    bool busy = false;
    bool in_fast = false; // the simulated fast-loop interrupt is running
    struct Frame {
        char dev;
        bool fast;
        uint32_t period;
    };
    std::vector<Frame> log;
    uint32_t period = 0u;
    int overlaps = 0;

    int frame(char dev, uint16_t tx, uint16_t *p_rx)
    {
        if (busy) {
            ++overlaps;
        }
        busy = true;
        log.push_back({dev, in_fast, period});
        uint16_t rx = 0u;
        int rc = 0;
        if (dev == 'D') {
            const mc_hal_spi_t s = drv.spi();
            rc = mc_hal_spi_transfer16(&s, tx, &rx);
        }
        busy = false;
        if (p_rx != nullptr) {
            *p_rx = rx;
        }
        return rc;
    }
    static int drv_t16(void *ctx, uint16_t tx, uint16_t *p_rx)
    {
        return static_cast<Bus *>(ctx)->frame('D', tx, p_rx);
    }
    static int enc_t16(void *ctx, uint16_t tx, uint16_t *p_rx)
    {
        return static_cast<Bus *>(ctx)->frame('E', tx, p_rx);
    }
    static inline const mc_hal_spi_ops_t drv_ops = {&Bus::drv_t16, nullptr};
    static inline const mc_hal_spi_ops_t enc_ops = {&Bus::enc_t16, nullptr};
};

struct Tick {
    uint32_t now = 0u;
    static int read(void *ctx, uint32_t *p)
    {
        auto *t = static_cast<Tick *>(ctx);
        *p = ++t->now; // time passes with every look at the clock
        return 0;
    }
    static int freq(void *, uint32_t *p)
    {
        *p = kTickHz;
        return 0;
    }
    static inline const mc_hal_tick_ops_t ops = {&Tick::read, &Tick::freq};
};

struct SchedTest : public ::testing::Test {
    Bus bus;
    Tick tick;
    mc_hal_tick_t tick_dev{&Tick::ops, &tick};
    mc_hal_spi_t drv_dev{&Bus::drv_ops, &bus};
    mc_hal_spi_t enc_dev{&Bus::enc_ops, &bus};
    mc_spisched_t sched{};
    uint32_t next_period_at = kPeriodTicks;
    bool fast_loop_runs = true;

    // The fast-loop interrupt: due every kPeriodTicks; runs to completion.
    static void wait(void *ctx)
    {
        auto *t = static_cast<SchedTest *>(ctx);
        t->tick.now += 1u;
        if (t->fast_loop_runs && t->tick.now >= t->next_period_at) {
            t->fast_period();
        }
    }
    void fast_period()
    {
        next_period_at += kPeriodTicks;
        bus.in_fast = true;
        bus.period++;
        uint16_t angle = 0u;
        (void)mc_hal_spi_transfer16(&enc_dev, 0xFFFFu, &angle); // the encoder
        (void)mc_spisched_fast_slot(&sched);                    // then one slow frame
        bus.in_fast = false;
    }

    void SetUp() override
    {
        mc_spisched_config_t c{};
        c.p_dev = &drv_dev;
        c.p_tick = &tick_dev;
        c.timeout_us = MC_SPISCHED_TIMEOUT_US_DEFAULT;
        c.wait = &SchedTest::wait;
        c.wait_ctx = this;
        ASSERT_EQ(mc_spisched_init(&sched, &c), 0);
    }
};

mc_drv8301_config_t odrive_cfg()
{
    mc_drv8301_config_t c{};
    c.gain = MC_DRV8301_GAIN_40;
    c.oc_adj_set = 21u;
    c.ocp_mode = MC_DRV8301_OCP_LATCH;
    c.pwm_mode = MC_DRV8301_PWM_6;
    c.gate_current = MC_DRV8301_GATE_1A7;
    c.octw_mode = MC_DRV8301_OCTW_OT_AND_OC;
    c.oc_toff = MC_DRV8301_OC_TOFF_CYCLE;
    return c;
}

} // namespace

TEST_F(SchedTest, InitRefusesBadConfigs)
{
    mc_spisched_t s{};
    mc_spisched_config_t c = sched.cfg;
    c.p_dev = nullptr;
    EXPECT_EQ(mc_spisched_init(&s, &c), -EINVAL);
    c = sched.cfg;
    c.p_tick = nullptr;
    EXPECT_EQ(mc_spisched_init(&s, &c), -EINVAL);
    c = sched.cfg;
    c.timeout_us = 0u;
    EXPECT_EQ(mc_spisched_init(&s, &c), -EINVAL);
    c.timeout_us = 1000001u;
    EXPECT_EQ(mc_spisched_init(&s, &c), -EINVAL);
}

// Boot (no fast loop yet): the slow handle is the device itself.
TEST_F(SchedTest, BeforeDeferFramesGoDirect)
{
    mc_drv8301_t drv{};
    const mc_drv8301_config_t c = odrive_cfg();
    ASSERT_EQ(mc_drv8301_init(&drv, &sched.dev, &c), 0);
    ASSERT_FALSE(bus.log.empty());
    for (const auto &f : bus.log) {
        EXPECT_EQ(f.dev, 'D');
        EXPECT_FALSE(f.fast);
        EXPECT_EQ(f.period, 0u); // no fast period ran
    }
    EXPECT_FALSE(mc_spisched_fast_slot(&sched)); // nothing posted
}

// Running: every gate-driver frame runs in the fast loop, after that
// period's encoder frame, at most one per period; the encoder gets its
// frame every period; nothing overlaps; the DRV8301 sees a correct
// conversation (its set-up verifies by reading back).
TEST_F(SchedTest, DeferredFramesRunInTheFastSlotOnePerPeriod)
{
    mc_drv8301_t drv{};
    const mc_drv8301_config_t c = odrive_cfg();
    ASSERT_EQ(mc_drv8301_init(&drv, &sched.dev, &c), 0);
    bus.log.clear();
    mc_spisched_defer(&sched);

    // The slow loop's re-arm after a gate kill: the set-up again.
    bus.drv.power_reset();
    ASSERT_EQ(mc_drv8301_init(&drv, &sched.dev, &c), 0);
    EXPECT_EQ(bus.drv.reg[2], drv.ctrl1);
    const uint32_t setup_periods = bus.period;

    // Supervision: the status registers (4 frames).
    bus.drv.reg[0] = 0x0440u; // FAULT | OTW
    uint32_t faults = 0u;
    const uint32_t p0 = bus.period;
    ASSERT_EQ(mc_drv8301_read_faults(&drv, &faults), 0);
    EXPECT_EQ(faults, MC_DRV8301_FAULT_FAULT | MC_DRV8301_FAULT_OTW);
    const uint32_t status_periods = bus.period - p0;

    EXPECT_EQ(bus.overlaps, 0);
    uint32_t drv_frames = 0u;
    std::vector<int> per_period(bus.period + 1u, 0);
    bool enc_first = true;
    for (size_t k = 0; k < bus.log.size(); ++k) {
        const auto &f = bus.log[k];
        EXPECT_TRUE(f.fast) << "frame " << k << " outside the fast loop";
        if (f.dev == 'D') {
            ++drv_frames;
            per_period[f.period]++;
            enc_first = enc_first && (k > 0) && (bus.log[k - 1].dev == 'E') &&
                        (bus.log[k - 1].period == f.period);
        }
    }
    EXPECT_TRUE(enc_first);
    for (int n : per_period) {
        EXPECT_LE(n, 1);
    }
    EXPECT_EQ(drv_frames, sched.n_slot_frames);
    // One frame per period: the status read (4 frames) takes 4 periods,
    // 200 us, inside one slow period (20): the supervision keeps its rate.
    EXPECT_EQ(status_periods, 4u);
    EXPECT_LT(status_periods, kSlowDivider);
    // The set-up: 2 writes and 2 reads of 2 frames, then the status
    // (4 frames): 10 frames, 10 periods.
    EXPECT_EQ(setup_periods, 10u);
    EXPECT_EQ(sched.n_timeouts, 0u);
}

// The fast loop has stopped: the slow side gives up after timeout_us with
// -EIO and withdraws the frame (a later slot runs nothing).
TEST_F(SchedTest, TimeoutWhenTheFastLoopStops)
{
    mc_spisched_defer(&sched);
    fast_loop_runs = false;
    uint16_t rx = 0x1111u;
    const uint32_t t0 = tick.now;
    EXPECT_EQ(mc_hal_spi_transfer16(&sched.dev, 0x8000u, &rx), -EIO);
    EXPECT_EQ(rx, 0x1111u);
    EXPECT_EQ(sched.n_timeouts, 1u);
    EXPECT_GE(tick.now - t0, MC_SPISCHED_TIMEOUT_US_DEFAULT);
    EXPECT_LE(tick.now - t0, MC_SPISCHED_TIMEOUT_US_DEFAULT + 4u); // a few clock reads
    EXPECT_FALSE(mc_spisched_fast_slot(&sched));
    EXPECT_TRUE(bus.log.empty());
}

// A device error in the slot reaches the slow side as the device's code.
TEST_F(SchedTest, DeviceErrorIsPassedBack)
{
    mc_spisched_defer(&sched);
    bus.drv.fail_at_frame = 0;
    uint16_t rx = 0x2222u;
    EXPECT_EQ(mc_hal_spi_transfer16(&sched.dev, 0x8000u, &rx), -EIO);
    EXPECT_EQ(rx, 0x2222u);
    EXPECT_EQ(sched.n_timeouts, 0u);
    EXPECT_EQ(sched.n_slot_frames, 1u);
}
