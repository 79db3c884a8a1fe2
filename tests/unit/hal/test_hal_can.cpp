// CAN through the fake: frame validation, FIFO queues of fixed capacity,
// bus state from the error counters.
#include <cerrno>
#include <cstring>

#include "hal_test_fixture.h"

namespace
{

mc_hal_can_frame_t Frame(uint32_t id, uint8_t len, uint8_t flags = 0u)
{
    mc_hal_can_frame_t f{};
    f.id = id;
    f.len = len;
    f.flags = flags;
    for (uint8_t i = 0; i < MC_HAL_CAN_FD_MAX_LEN; ++i) {
        f.data[i] = static_cast<uint8_t>(id + i);
    }
    return f;
}

void ExpectSameFrame(const mc_hal_can_frame_t &want, const mc_hal_can_frame_t &got)
{
    EXPECT_EQ(want.id, got.id);
    EXPECT_EQ(want.len, got.len);
    EXPECT_EQ(want.flags, got.flags);
    EXPECT_EQ(0, std::memcmp(want.data, got.data, want.len));
}

TEST_F(HalFake, CanSendClassicFramesInOrder)
{
    const mc_hal_can_frame_t a = Frame(0x7FFu, 8u);                           // max std id
    const mc_hal_can_frame_t b = Frame(0x1FFFFFFFu, 0u, MC_HAL_CAN_FLAG_EXT); // max ext id
    const mc_hal_can_frame_t c = Frame(0x123u, 4u, MC_HAL_CAN_FLAG_RTR);
    ASSERT_EQ(0, mc_hal_can_send(hal->can, &a));
    ASSERT_EQ(0, mc_hal_can_send(hal->can, &b));
    ASSERT_EQ(0, mc_hal_can_send(hal->can, &c));

    mc_hal_can_frame_t got{};
    ASSERT_EQ(0, mc_hal_fake_can_tx_pop(&fake, &got));
    ExpectSameFrame(a, got);
    ASSERT_EQ(0, mc_hal_fake_can_tx_pop(&fake, &got));
    ExpectSameFrame(b, got);
    ASSERT_EQ(0, mc_hal_fake_can_tx_pop(&fake, &got));
    ExpectSameFrame(c, got);
    EXPECT_EQ(-EAGAIN, mc_hal_fake_can_tx_pop(&fake, &got));
}

TEST_F(HalFake, CanSendRejectsInvalidFramesAndQueuesNothing)
{
    struct Case {
        const char *what;
        mc_hal_can_frame_t f;
        int rc;
    };
    const Case cases[] = {
        {"std id beyond 11 bits", Frame(0x800u, 1u), -EINVAL},
        {"ext id beyond 29 bits", Frame(0x20000000u, 1u, MC_HAL_CAN_FLAG_EXT), -EINVAL},
        {"classic len 9", Frame(0x100u, 9u), -EINVAL},
        {"classic len 64", Frame(0x100u, 64u), -EINVAL},
        {"unknown flag bit", Frame(0x100u, 1u, 1u << 4), -EINVAL},
        {"BRS without FD", Frame(0x100u, 1u, MC_HAL_CAN_FLAG_BRS), -EINVAL},
        {"FD with bad len 9", Frame(0x100u, 9u, MC_HAL_CAN_FLAG_FD), -EINVAL},
        {"FD remote frame", Frame(0x100u, 8u, MC_HAL_CAN_FLAG_FD | MC_HAL_CAN_FLAG_RTR), -EINVAL},
        {"FD on classic controller", Frame(0x100u, 64u, MC_HAL_CAN_FLAG_FD), -ENOTSUP},
    };
    for (const Case &c : cases) {
        SCOPED_TRACE(c.what);
        EXPECT_EQ(c.rc, mc_hal_can_send(hal->can, &c.f));
        EXPECT_EQ(0u, fake.can_tx.count);
        // The rx side validates the same way.
        EXPECT_EQ(c.rc, mc_hal_fake_can_rx_push(&fake, &c.f));
        EXPECT_EQ(0u, fake.can_rx.count);
    }
}

TEST_F(HalFake, CanFdFramesOnAnFdCapableController)
{
    cfg.can_fd_capable = true;
    ASSERT_EQ(0, mc_hal_fake_init(&fake, &cfg));
    mc_hal_can_status_t st{};
    ASSERT_EQ(0, mc_hal_can_get_status(hal->can, &st));
    EXPECT_TRUE(st.fd_capable);

    const mc_hal_can_frame_t f64 =
        Frame(0x1234567u, 64u, MC_HAL_CAN_FLAG_FD | MC_HAL_CAN_FLAG_BRS | MC_HAL_CAN_FLAG_EXT);
    const mc_hal_can_frame_t f12 = Frame(0x10u, 12u, MC_HAL_CAN_FLAG_FD);
    ASSERT_EQ(0, mc_hal_can_send(hal->can, &f64));
    ASSERT_EQ(0, mc_hal_can_send(hal->can, &f12));
    const mc_hal_can_frame_t f13 = Frame(0x10u, 13u, MC_HAL_CAN_FLAG_FD);
    EXPECT_EQ(-EINVAL, mc_hal_can_send(hal->can, &f13));

    mc_hal_can_frame_t got{};
    ASSERT_EQ(0, mc_hal_fake_can_tx_pop(&fake, &got));
    ExpectSameFrame(f64, got);
    ASSERT_EQ(0, mc_hal_fake_can_tx_pop(&fake, &got));
    ExpectSameFrame(f12, got);
    EXPECT_EQ(-EAGAIN, mc_hal_fake_can_tx_pop(&fake, &got));
}

TEST(HalCan, FdLengthTable)
{
    int valid = 0;
    for (unsigned len = 0; len <= 255u; ++len) {
        if (mc_hal_can_fd_len_valid(static_cast<uint8_t>(len))) {
            ++valid;
        }
    }
    EXPECT_EQ(16, valid); // one per DLC code 0..15
    EXPECT_TRUE(mc_hal_can_fd_len_valid(48u));
    EXPECT_FALSE(mc_hal_can_fd_len_valid(63u));
    EXPECT_FALSE(mc_hal_can_fd_len_valid(65u));
    EXPECT_EQ(-EINVAL, mc_hal_can_frame_check(nullptr, true));
}

TEST_F(HalFake, CanTxQueueFullIsENOBUFSAndFifoSurvivesWrapAround)
{
    for (uint32_t i = 0; i < MC_HAL_FAKE_CAN_QUEUE_LEN; ++i) {
        const mc_hal_can_frame_t f = Frame(i, 1u);
        ASSERT_EQ(0, mc_hal_can_send(hal->can, &f));
    }
    const mc_hal_can_frame_t extra = Frame(0x55u, 1u);
    EXPECT_EQ(-ENOBUFS, mc_hal_can_send(hal->can, &extra));
    EXPECT_EQ(MC_HAL_FAKE_CAN_QUEUE_LEN, fake.can_tx.count);

    // Drain three, queue three more: the ring wraps; order must hold.
    mc_hal_can_frame_t got{};
    for (uint32_t i = 0; i < 3u; ++i) {
        ASSERT_EQ(0, mc_hal_fake_can_tx_pop(&fake, &got));
        EXPECT_EQ(i, got.id);
    }
    for (uint32_t i = 0; i < 3u; ++i) {
        const mc_hal_can_frame_t f = Frame(0x100u + i, 1u);
        ASSERT_EQ(0, mc_hal_can_send(hal->can, &f));
    }
    EXPECT_EQ(-ENOBUFS, mc_hal_can_send(hal->can, &extra));
    for (uint32_t i = 3; i < MC_HAL_FAKE_CAN_QUEUE_LEN; ++i) {
        ASSERT_EQ(0, mc_hal_fake_can_tx_pop(&fake, &got));
        EXPECT_EQ(i, got.id);
    }
    for (uint32_t i = 0; i < 3u; ++i) {
        ASSERT_EQ(0, mc_hal_fake_can_tx_pop(&fake, &got));
        EXPECT_EQ(0x100u + i, got.id);
    }
    EXPECT_EQ(-EAGAIN, mc_hal_fake_can_tx_pop(&fake, &got));
}

TEST_F(HalFake, CanReceiveEmptyIsEAGAINAndFullRxCountsOverruns)
{
    mc_hal_can_frame_t got = Frame(0x3AAu, 3u);
    EXPECT_EQ(-EAGAIN, mc_hal_can_receive(hal->can, &got));
    EXPECT_EQ(0x3AAu, got.id); // untouched

    ASSERT_EQ(0, mc_hal_fake_tick_set(&fake, 4242u));
    for (uint32_t i = 0; i < MC_HAL_FAKE_CAN_QUEUE_LEN; ++i) {
        const mc_hal_can_frame_t f = Frame(0x200u + i, 8u);
        ASSERT_EQ(0, mc_hal_fake_can_rx_push(&fake, &f));
    }
    const mc_hal_can_frame_t lost = Frame(0x2FFu, 8u);
    EXPECT_EQ(-ENOBUFS, mc_hal_fake_can_rx_push(&fake, &lost));
    mc_hal_can_status_t st{};
    ASSERT_EQ(0, mc_hal_can_get_status(hal->can, &st));
    EXPECT_EQ(1u, st.rx_overrun_count);

    for (uint32_t i = 0; i < MC_HAL_FAKE_CAN_QUEUE_LEN; ++i) {
        ASSERT_EQ(0, mc_hal_can_receive(hal->can, &got));
        ExpectSameFrame(Frame(0x200u + i, 8u), got);
        EXPECT_EQ(4242u, got.timestamp_ticks); // stamped at reception
    }
    EXPECT_EQ(-EAGAIN, mc_hal_can_receive(hal->can, &got));
}

TEST_F(HalFake, CanBusStateFollowsErrorCounters)
{
    struct Case {
        uint16_t tec, rec;
        mc_hal_can_bus_state_t state;
    };
    // ISO 11898-1 thresholds: warning at 96, passive at 128, bus-off > 255.
    const Case cases[] = {
        {0, 0, MC_HAL_CAN_STATE_ERROR_ACTIVE},      {95, 95, MC_HAL_CAN_STATE_ERROR_ACTIVE},
        {96, 0, MC_HAL_CAN_STATE_ERROR_WARNING},    {0, 96, MC_HAL_CAN_STATE_ERROR_WARNING},
        {127, 127, MC_HAL_CAN_STATE_ERROR_WARNING}, {128, 0, MC_HAL_CAN_STATE_ERROR_PASSIVE},
        {0, 128, MC_HAL_CAN_STATE_ERROR_PASSIVE},   {255, 0, MC_HAL_CAN_STATE_ERROR_PASSIVE},
        {256, 0, MC_HAL_CAN_STATE_BUS_OFF},
    };
    for (const Case &c : cases) {
        SCOPED_TRACE(testing::Message() << "tec " << c.tec << " rec " << c.rec);
        ASSERT_EQ(0, mc_hal_fake_can_set_errors(&fake, c.tec, c.rec));
        mc_hal_can_status_t st{};
        ASSERT_EQ(0, mc_hal_can_get_status(hal->can, &st));
        EXPECT_EQ(c.state, st.state);
        EXPECT_EQ(c.tec, st.tx_err_count);
        EXPECT_EQ(c.rec, st.rx_err_count);
    }
}

TEST_F(HalFake, CanSendWhileBusOffIsENETDOWNButErrorPassiveStillSends)
{
    const mc_hal_can_frame_t f = Frame(0x10u, 2u);
    ASSERT_EQ(0, mc_hal_fake_can_set_errors(&fake, 200u, 0u)); // passive
    EXPECT_EQ(0, mc_hal_can_send(hal->can, &f));
    ASSERT_EQ(0, mc_hal_fake_can_set_errors(&fake, 256u, 0u)); // bus-off
    EXPECT_EQ(-ENETDOWN, mc_hal_can_send(hal->can, &f));
    EXPECT_EQ(1u, fake.can_tx.count);
    ASSERT_EQ(0, mc_hal_fake_can_set_errors(&fake, 0u, 0u)); // recovered
    EXPECT_EQ(0, mc_hal_can_send(hal->can, &f));
    EXPECT_EQ(2u, fake.can_tx.count);
}

TEST_F(HalFake, CanInjectedErrorsChangeNothing)
{
    const mc_hal_can_frame_t f = Frame(0x10u, 2u);
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_CAN_SEND, -EIO, 1u));
    EXPECT_EQ(-EIO, mc_hal_can_send(hal->can, &f));
    EXPECT_EQ(0u, fake.can_tx.count);

    ASSERT_EQ(0, mc_hal_fake_can_rx_push(&fake, &f));
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_CAN_RECEIVE, -EIO, 1u));
    mc_hal_can_frame_t got = Frame(0x3AAu, 3u);
    EXPECT_EQ(-EIO, mc_hal_can_receive(hal->can, &got));
    EXPECT_EQ(0x3AAu, got.id);
    EXPECT_EQ(1u, fake.can_rx.count); // still there
    ASSERT_EQ(0, mc_hal_can_receive(hal->can, &got));
    EXPECT_EQ(0x10u, got.id);
}

} // namespace
