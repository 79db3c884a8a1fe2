// can on bxCAN against a register file in RAM: bit timing, filters, tx
// mailboxes, rx FIFO decoding, error states. Register facts: RM0090 §32.
#include <gtest/gtest.h>

#include "f405_test_util.h"

namespace
{

constexpr uint32_t kApb1Hz = 42000000u; // APB1 at 168 MHz SYSCLK / 4

struct Btr {
    uint32_t brp, bs1, bs2, sjw;
};

// Field decoding straight from RM0090 §32.9.2 (CAN_BTR).
Btr decode(uint32_t btr)
{
    return {(btr & 0x3FFu) + 1u, ((btr >> 16) & 0xFu) + 1u, ((btr >> 20) & 0x7u) + 1u,
            ((btr >> 24) & 0x3u) + 1u};
}

const mc_f405_can_filter_t kFilters[] = {
    {0x120u, 0x7E0u, false},          // ODrive-style node 9: ids 0x120..0x13F
    {0x18FF0000u, 0x1FFFFFFFu, true}, // one 29-bit id
};

mc_hal_can_frame_t frame(uint32_t id, uint8_t len, uint8_t flags)
{
    mc_hal_can_frame_t f{};
    f.id = id;
    f.len = len;
    f.flags = flags;
    for (uint8_t k = 0; k < 8; ++k) {
        f.data[k] = static_cast<uint8_t>(0x10u * (k + 1u));
    }
    return f;
}

struct CanBoard : public ::testing::Test {
    mc_f405_can_regs_t can{};
    mc_f405_tim_regs_t tim2{};
    mc_f405_tick_t tick{};
    mc_f405_can_t drv{};

    mc_f405_can_config_t cfg()
    {
        mc_f405_can_config_t c{};
        c.p_can = &can;
        c.pclk_hz = kApb1Hz;
        c.bitrate_bps = 500000u;
        c.sample_point_permille = 875u;
        c.sjw_tq = 1u;
        c.auto_bus_off_recovery = true;
        c.no_auto_retransmit = false;
        c.p_filters = kFilters;
        c.n_filters = 2u;
        c.filter_bank_start = 0u;
        c.rx_irq = false;
        c.p_tick = &tick.dev;
        return c;
    }

    void SetUp() override
    {
        const mc_f405_tick_config_t tc{&tim2, 84000000u, 0u};
        ASSERT_EQ(mc_f405_tick_init(&tick, &tc), 0);
    }

    // Initialise with the hardware acknowledging init mode, then play the
    // controller joining the bus (INAK clears) with three empty mailboxes.
    void start(const mc_f405_can_config_t &c)
    {
        can.MSR = MC_F405_CAN_MSR_INAK;
        ASSERT_EQ(mc_f405_can_init(&drv, &c), 0);
        can.MSR = 0u;
        can.TSR = MC_F405_CAN_TSR_TME(0) | MC_F405_CAN_TSR_TME(1) | MC_F405_CAN_TSR_TME(2);
    }

    int send(const mc_hal_can_frame_t &f)
    {
        return mc_hal_can_send(&drv.dev, &f);
    }

    // A frame arrives in FIFO 0 (one pending).
    void arrive(uint32_t rir, uint32_t dlc, uint32_t lo, uint32_t hi)
    {
        can.RX[0].RIR = rir;
        can.RX[0].RDTR = dlc | (1u << 8); // FMI = 1, ignored
        can.RX[0].RDLR = lo;
        can.RX[0].RDHR = hi;
        can.RF0R = 1u;
    }
};

} // namespace

// ---- bit timing -----------------------------------------------------------

// 500 kbit/s at 42 MHz: 84 clocks per bit. Prescaler 6 gives 14 tq; sample
// point at 87.5 % of 14 = 12.25 -> 1 + BS1 = 12: BS1 = 11, BS2 = 2 (85.7 %).
// BTR = BRP 5 | TS1 10 << 16 | TS2 1 << 20 | SJW 0 << 24 = 0x001A0005.
// 1 Mbit/s: 42 clocks, prescaler 3, same 14 tq split -> 0x001A0002.
TEST(F405CanTiming, Btr500kAnd1MAt42MHz)
{
    uint32_t btr = 0u;
    ASSERT_EQ(mc_f405_can_bit_timing(kApb1Hz, 500000u, 875u, 1u, &btr), 0);
    EXPECT_EQ(btr, 0x001A0005u);
    ASSERT_EQ(mc_f405_can_bit_timing(kApb1Hz, 1000000u, 875u, 1u, &btr), 0);
    EXPECT_EQ(btr, 0x001A0002u);
    ASSERT_EQ(mc_f405_can_bit_timing(kApb1Hz, 500000u, 875u, 2u, &btr), 0);
    EXPECT_EQ(btr, 0x011A0005u); // SJW = 2 tq
}

// For common rates the decoded register gives the exact bit rate, a legal
// segment split, and a sample point within 2.5 % of the 87.5 % asked for
// (the best any split of these tq counts can do at these rates).
TEST(F405CanTiming, ExactRatesAndSamplePoint)
{
    for (uint32_t rate : {125000u, 250000u, 500000u, 1000000u}) {
        uint32_t btr = 0u;
        ASSERT_EQ(mc_f405_can_bit_timing(kApb1Hz, rate, 875u, 1u, &btr), 0) << rate;
        const Btr b = decode(btr);
        const uint32_t n = 1u + b.bs1 + b.bs2;
        EXPECT_EQ(b.brp * n * rate, kApb1Hz) << rate;
        EXPECT_GE(n, 8u);
        EXPECT_LE(n, 25u);
        EXPECT_LE(b.bs1, 16u);
        EXPECT_LE(b.bs2, 8u);
        const double sp = (1.0 + b.bs1) / n;
        EXPECT_NEAR(sp, 0.875, 0.025) << rate;
    }
}

TEST(F405CanTiming, ImpossibleRatesRejected)
{
    uint32_t btr = 0xDEADu;
    // 42e6 / 333333 is not an integer number of clocks per bit.
    EXPECT_EQ(mc_f405_can_bit_timing(kApb1Hz, 333333u, 875u, 1u, &btr), -EINVAL);
    // 5 Mbit/s: 8.4 clocks per bit, fewer than 8 tq possible.
    EXPECT_EQ(mc_f405_can_bit_timing(kApb1Hz, 5000000u, 875u, 1u, &btr), -EINVAL);
    EXPECT_EQ(mc_f405_can_bit_timing(kApb1Hz, 500000u, 875u, 5u, &btr), -EINVAL);
    EXPECT_EQ(mc_f405_can_bit_timing(kApb1Hz, 500000u, 400u, 1u, &btr), -EINVAL);
    EXPECT_EQ(btr, 0xDEADu);
}

// ---- init -------------------------------------------------------------------

TEST_F(CanBoard, InitRegisterWrites)
{
    start(cfg());
    EXPECT_EQ(can.BTR, 0x001A0005u);
    // MCR: INRQ cleared (normal mode requested), TXFP (bit 2) for request
    // order, ABOM (bit 6), SLEEP (bit 1) cleared, NART clear.
    EXPECT_EQ(can.MCR, (1u << 2) | (1u << 6));
    EXPECT_EQ(can.IER, 0u);
    // Filter banks 0 and 1: mask mode (FM1R 0), 32-bit (FS1R), FIFO 0
    // (FFA1R 0), active (FA1R), FINIT cleared.
    EXPECT_EQ(can.FM1R, 0u);
    EXPECT_EQ(can.FS1R, 3u);
    EXPECT_EQ(can.FFA1R, 0u);
    EXPECT_EQ(can.FA1R, 3u);
    EXPECT_EQ(can.FMR & MC_F405_CAN_FMR_FINIT, 0u);
    // Bank 0, 11-bit: STID at bits 31:21; the mask also compares IDE (bit 2).
    EXPECT_EQ(can.FB[0].FR1, 0x120u << 21);
    EXPECT_EQ(can.FB[0].FR2, (0x7E0u << 21) | 4u);
    // Bank 1, 29-bit: EXID at bits 31:3, IDE set in id and mask.
    EXPECT_EQ(can.FB[1].FR1, (0x18FF0000u << 3) | 4u);
    EXPECT_EQ(can.FB[1].FR2, (0x1FFFFFFFu << 3) | 4u);
    EXPECT_EQ(can.FB[2].FR1, 0u); // untouched
}

TEST_F(CanBoard, NoFiltersAcceptsAll)
{
    mc_f405_can_config_t c = cfg();
    c.p_filters = nullptr;
    c.n_filters = 0u;
    c.rx_irq = true;
    c.bitrate_bps = 1000000u;
    start(c);
    EXPECT_EQ(can.BTR, 0x001A0002u);
    EXPECT_EQ(can.FA1R, 1u);
    EXPECT_EQ(can.FB[0].FR1, 0u);
    EXPECT_EQ(can.FB[0].FR2, 0u); // mask 0: every frame
    EXPECT_EQ(can.IER, MC_F405_CAN_IER_FMPIE0);
}

TEST_F(CanBoard, NodeFilterSetAtRunTime)
{
    // Booted accepting everything (bank 0), then the application's node
    // filter for node 5: id 5 << 5 = 0xA0 under mask 0x7E0 (the node bits).
    mc_f405_can_config_t c = cfg();
    c.p_filters = nullptr;
    c.n_filters = 0u;
    start(c);
    static const mc_f405_can_filter_t node5[1] = {{0xA0u, 0x7E0u, false}};
    ASSERT_EQ(0, mc_f405_can_set_filters(&drv, node5, 1u));
    EXPECT_EQ(can.FA1R, 1u);
    EXPECT_EQ(can.FS1R & 1u, 1u);
    EXPECT_EQ(can.FB[0].FR1, 0xA0u << 21);
    EXPECT_EQ(can.FB[0].FR2, (0x7E0u << 21) | 4u);
    EXPECT_EQ(can.FMR & MC_F405_CAN_FMR_FINIT, 0u);
    // From two banks to one: bank 1 deactivated.
    start(cfg());
    ASSERT_EQ(can.FA1R, 3u);
    ASSERT_EQ(0, mc_f405_can_set_filters(&drv, node5, 1u));
    EXPECT_EQ(can.FA1R, 1u);
    // An invalid filter writes nothing.
    static const mc_f405_can_filter_t bad[1] = {{0x800u, 0x7E0u, false}};
    const uint32_t fr1 = can.FB[0].FR1;
    EXPECT_EQ(-EINVAL, mc_f405_can_set_filters(&drv, bad, 1u));
    EXPECT_EQ(fr1, can.FB[0].FR1);
}

TEST_F(CanBoard, InitModeNeverAcknowledgedIsIoError)
{
    const mc_f405_can_config_t c = cfg();
    can.MSR = 0u; // INAK never set: no clock or held in reset
    EXPECT_EQ(mc_f405_can_init(&drv, &c), -EIO);
    EXPECT_EQ(can.BTR, 0u); // nothing programmed
}

TEST_F(CanBoard, InvalidConfigWritesNothing)
{
    poison(drv);
    const auto drv0 = snapshot(drv);
    const auto regs0 = snapshot(can);
    const mc_f405_can_filter_t bad[] = {{0x800u, 0x7FFu, false}}; // 12-bit id
    mc_f405_can_config_t c = cfg();
    c.p_filters = bad;
    c.n_filters = 1u;
    EXPECT_EQ(mc_f405_can_init(&drv, &c), -EINVAL);
    c = cfg();
    c.bitrate_bps = 333333u;
    EXPECT_EQ(mc_f405_can_init(&drv, &c), -EINVAL);
    c = cfg();
    c.filter_bank_start = 27u; // two filters from bank 27: past bank 27
    EXPECT_EQ(mc_f405_can_init(&drv, &c), -EINVAL);
    c = cfg();
    c.p_filters = nullptr;
    EXPECT_EQ(mc_f405_can_init(&drv, &c), -EINVAL);
    EXPECT_EQ(snapshot(drv), drv0);
    EXPECT_EQ(snapshot(can), regs0);
}

// ---- send -------------------------------------------------------------------

TEST_F(CanBoard, SendFillsMailboxesThenNoBufs)
{
    start(cfg());

    // 11-bit data frame -> mailbox 0: DLC 3, bytes little-endian in TDLR,
    // TIR = STID << 21 | TXRQ written last.
    ASSERT_EQ(send(frame(0x123u, 3u, 0u)), 0);
    EXPECT_EQ(can.TX[0].TDTR, 3u);
    EXPECT_EQ(can.TX[0].TDLR, 0x00302010u); // bytes beyond len sent as 0
    EXPECT_EQ(can.TX[0].TDHR, 0u);
    EXPECT_EQ(can.TX[0].TIR, (0x123u << 21) | 1u);
    can.TSR = can.TSR & ~MC_F405_CAN_TSR_TME(0); // hardware: mailbox 0 busy

    // 29-bit remote frame -> mailbox 1: EXID << 3 | IDE | RTR | TXRQ.
    ASSERT_EQ(send(frame(0x1ABCDE0u, 2u, MC_HAL_CAN_FLAG_EXT | MC_HAL_CAN_FLAG_RTR)), 0);
    EXPECT_EQ(can.TX[1].TIR, (0x1ABCDE0u << 3) | 4u | 2u | 1u);
    EXPECT_EQ(can.TX[1].TDTR, 2u);
    EXPECT_EQ(can.TX[1].TDLR, 0u); // no data in a remote frame
    can.TSR = can.TSR & ~MC_F405_CAN_TSR_TME(1);

    // 8 bytes -> mailbox 2.
    ASSERT_EQ(send(frame(0x7FFu, 8u, 0u)), 0);
    EXPECT_EQ(can.TX[2].TDLR, 0x40302010u);
    EXPECT_EQ(can.TX[2].TDHR, 0x80706050u);
    EXPECT_EQ(can.TX[2].TIR, (0x7FFu << 21) | 1u);
    can.TSR = can.TSR & ~MC_F405_CAN_TSR_TME(2);

    // All three mailboxes pending: -ENOBUFS, nothing written.
    const auto regs0 = snapshot(can);
    EXPECT_EQ(send(frame(0x100u, 1u, 0u)), -ENOBUFS);
    EXPECT_EQ(snapshot(can), regs0);

    // Mailbox 1 done (TME1 set by the hardware): the next frame goes there.
    can.TSR = can.TSR | MC_F405_CAN_TSR_TME(1);
    ASSERT_EQ(send(frame(0x100u, 1u, 0u)), 0);
    EXPECT_EQ(can.TX[1].TIR, (0x100u << 21) | 1u);
}

TEST_F(CanBoard, SendRejectsBadFramesAndBusOff)
{
    start(cfg());
    const auto regs0 = snapshot(can);
    EXPECT_EQ(send(frame(0x800u, 1u, 0u)), -EINVAL); // 12-bit id
    EXPECT_EQ(send(frame(0x100u, 9u, 0u)), -EINVAL);
    EXPECT_EQ(send(frame(0x100u, 12u, MC_HAL_CAN_FLAG_FD)), -ENOTSUP);
    EXPECT_EQ(snapshot(can), regs0);

    // Bus-off reported by the controller (ESR.BOFF, TEC 255): -ENETDOWN.
    can.ESR = MC_F405_CAN_ESR_BOFF | MC_F405_CAN_ESR_EPVF | MC_F405_CAN_ESR_EWGF | (255u << 16);
    const auto regs1 = snapshot(can);
    EXPECT_EQ(send(frame(0x100u, 1u, 0u)), -ENETDOWN);
    EXPECT_EQ(snapshot(can), regs1);

    // Still in initialisation mode (never synchronised): -EIO.
    can.ESR = 0u;
    can.MSR = MC_F405_CAN_MSR_INAK;
    EXPECT_EQ(send(frame(0x100u, 1u, 0u)), -EIO);
}

// ---- status -----------------------------------------------------------------

TEST_F(CanBoard, ErrorStatesFromEsr)
{
    start(cfg());
    struct Case {
        uint32_t esr;
        mc_hal_can_bus_state_t state;
        uint16_t tec, rec;
    };
    const Case cases[] = {
        {(5u << 16) | (3u << 24), MC_HAL_CAN_STATE_ERROR_ACTIVE, 5u, 3u},
        {MC_F405_CAN_ESR_EWGF | (100u << 16), MC_HAL_CAN_STATE_ERROR_WARNING, 100u, 0u},
        {MC_F405_CAN_ESR_EWGF | MC_F405_CAN_ESR_EPVF | (130u << 24), MC_HAL_CAN_STATE_ERROR_PASSIVE,
         0u, 130u},
        {MC_F405_CAN_ESR_EWGF | MC_F405_CAN_ESR_EPVF | MC_F405_CAN_ESR_BOFF | (248u << 16),
         MC_HAL_CAN_STATE_BUS_OFF, 248u, 0u},
        // LEC bits (6:4) do not disturb the decoding.
        {(5u << 4) | (1u << 16), MC_HAL_CAN_STATE_ERROR_ACTIVE, 1u, 0u},
    };
    for (const Case &c : cases) {
        can.ESR = c.esr;
        mc_hal_can_status_t st{};
        ASSERT_EQ(mc_hal_can_get_status(&drv.dev, &st), 0);
        EXPECT_EQ(st.state, c.state) << std::hex << c.esr;
        EXPECT_EQ(st.tx_err_count, c.tec);
        EXPECT_EQ(st.rx_err_count, c.rec);
        EXPECT_FALSE(st.fd_capable);
    }
}

// ---- receive ------------------------------------------------------------------

TEST_F(CanBoard, ReceiveDecodesFifo)
{
    start(cfg());
    mc_hal_can_frame_t f{};
    f.id = 0xABCu;
    EXPECT_EQ(mc_hal_can_receive(&drv.dev, &f), -EAGAIN);
    EXPECT_EQ(f.id, 0xABCu);

    tim2.CNT = 4242u;
    arrive(0x321u << 21, 8u, 0x44332211u, 0x88776655u);
    ASSERT_EQ(mc_hal_can_receive(&drv.dev, &f), 0);
    EXPECT_EQ(f.id, 0x321u);
    EXPECT_EQ(f.flags, 0u);
    EXPECT_EQ(f.len, 8u);
    const uint8_t want[8] = {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88};
    for (int k = 0; k < 8; ++k) {
        EXPECT_EQ(f.data[k], want[k]) << k;
    }
    EXPECT_EQ(f.timestamp_ticks, 4242u);
    EXPECT_EQ(can.RF0R, MC_F405_CAN_RFR_RFOM); // output mailbox released
    // (In RAM the RFOM write also zeroed FMP0, as the hardware would with
    // one frame pending.)
    EXPECT_EQ(mc_hal_can_receive(&drv.dev, &f), -EAGAIN);

    // 29-bit remote frame with DLC 4.
    arrive((0x1234567u << 3) | 4u | 2u, 4u, 0u, 0u);
    ASSERT_EQ(mc_hal_can_receive(&drv.dev, &f), 0);
    EXPECT_EQ(f.id, 0x1234567u);
    EXPECT_EQ(f.flags, MC_HAL_CAN_FLAG_EXT | MC_HAL_CAN_FLAG_RTR);
    EXPECT_EQ(f.len, 4u);

    // A classic DLC above 8 still carries 8 bytes.
    arrive(0x10u << 21, 12u, 0u, 0u);
    ASSERT_EQ(mc_hal_can_receive(&drv.dev, &f), 0);
    EXPECT_EQ(f.len, 8u);
}

TEST_F(CanBoard, OverrunCounted)
{
    start(cfg());
    arrive(0x55u << 21, 1u, 0x99u, 0u);
    can.RF0R = 3u | MC_F405_CAN_RFR_FULL | MC_F405_CAN_RFR_FOVR; // hardware
    mc_hal_can_frame_t f{};
    ASSERT_EQ(mc_hal_can_receive(&drv.dev, &f), 0);
    EXPECT_EQ(f.id, 0x55u);
    EXPECT_EQ(f.data[0], 0x99u);
    mc_hal_can_status_t st{};
    ASSERT_EQ(mc_hal_can_get_status(&drv.dev, &st), 0);
    EXPECT_EQ(st.rx_overrun_count, 1u);
}

// Interrupt mode: the FIFO 0 ISR moves frames into the ring, receive pops
// them in order; a full ring counts lost frames.
TEST_F(CanBoard, IsrRing)
{
    mc_f405_can_config_t c = cfg();
    c.rx_irq = true;
    start(c);

    for (uint32_t k = 0; k < 3; ++k) {
        arrive((0x100u + k) << 21, 1u, k, 0u);
        mc_f405_can_rx_isr(&drv);
        EXPECT_EQ(can.RF0R, MC_F405_CAN_RFR_RFOM);
    }
    mc_hal_can_frame_t f{};
    for (uint32_t k = 0; k < 3; ++k) {
        ASSERT_EQ(mc_hal_can_receive(&drv.dev, &f), 0);
        EXPECT_EQ(f.id, 0x100u + k);
        EXPECT_EQ(f.data[0], k);
    }
    EXPECT_EQ(mc_hal_can_receive(&drv.dev, &f), -EAGAIN);

    // The ring holds MC_F405_CAN_RX_RING_LEN - 1 frames.
    for (uint32_t k = 0; k < MC_F405_CAN_RX_RING_LEN; ++k) {
        arrive(0x200u << 21, 0u, 0u, 0u);
        mc_f405_can_rx_isr(&drv);
    }
    mc_hal_can_status_t st{};
    ASSERT_EQ(mc_hal_can_get_status(&drv.dev, &st), 0);
    EXPECT_EQ(st.rx_overrun_count, 1u);
    uint32_t n = 0;
    while (mc_hal_can_receive(&drv.dev, &f) == 0) {
        ++n;
    }
    EXPECT_EQ(n, MC_F405_CAN_RX_RING_LEN - 1u);
}
