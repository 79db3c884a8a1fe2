/**
 * @file mc_hal_fake.c
 * @brief Fake HAL board for tests (see mc_hal_fake.h).
 *
 * Every op follows the same pattern: check pointers, count the call, return
 * an injected error if one is armed (without any effect), validate the
 * arguments completely, and only then change state. That order is what
 * keeps "a rejected call changes nothing" true by construction.
 */
#include "mc_hal_fake.h"

#include <errno.h>
#include <stddef.h>
#include <string.h>

/* ---- common ------------------------------------------------------------ */

/* Count the call; return the armed injected error (consuming it) or 0. */
static int fake_enter(mc_hal_fake_t *f, mc_hal_fake_call_t call)
{
    f->call_count[call]++;
    if (f->inject_remaining[call] > 0u) {
        f->inject_remaining[call]--;
        return f->inject_err[call];
    }
    return 0;
}

static bool period_valid(float period_s)
{
    /* NaN fails both comparisons; +inf fails the second. */
    return (period_s > 0.0f) && (period_s <= 1.0f);
}

/* ---- adc --------------------------------------------------------------- */

static int fake_adc_read(void *ctx, mc_hal_adc_sample_t *p_sample)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if ((f == NULL) || (p_sample == NULL)) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_ADC_READ);
    if (rc != 0) {
        return rc;
    }
    if (!f->adc_pending) {
        return -EAGAIN;
    }
    *p_sample = f->adc_sample;
    f->adc_pending = false;
    return 0;
}

static int fake_adc_read_temp(void *ctx, mc_hal_adc_temp_t *p_temp)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if ((f == NULL) || (p_temp == NULL)) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_ADC_READ_TEMP);
    if (rc != 0) {
        return rc;
    }
    *p_temp = f->adc_temp;
    return 0;
}

static const mc_hal_adc_ops_t fake_adc_ops = {
    .read = fake_adc_read,
    .read_temp = fake_adc_read_temp,
};

/* ---- pwm3 -------------------------------------------------------------- */

static int fake_pwm3_set_duty(void *ctx, float duty_a, float duty_b, float duty_c)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if (f == NULL) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_PWM3_SET_DUTY);
    if (rc != 0) {
        return rc;
    }
    if (!mc_hal_pwm3_duty_valid(duty_a) || !mc_hal_pwm3_duty_valid(duty_b) ||
        !mc_hal_pwm3_duty_valid(duty_c)) {
        return -EINVAL;
    }
    f->pwm3.duty_a = duty_a;
    f->pwm3.duty_b = duty_b;
    f->pwm3.duty_c = duty_c;
    return 0;
}

static int fake_pwm3_enable(void *ctx)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if (f == NULL) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_PWM3_ENABLE);
    if (rc != 0) {
        return rc;
    }
    if (f->fault.gate_killed) {
        return -EBUSY;
    }
    f->pwm3.enabled = true;
    return 0;
}

static int fake_pwm3_disable(void *ctx)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if (f == NULL) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_PWM3_DISABLE);
    if (rc != 0) {
        return rc;
    }
    f->pwm3.enabled = false;
    return 0;
}

static int fake_pwm3_get_state(void *ctx, mc_hal_pwm3_state_t *p_state)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if ((f == NULL) || (p_state == NULL)) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_PWM3_GET_STATE);
    if (rc != 0) {
        return rc;
    }
    *p_state = f->pwm3;
    return 0;
}

static const mc_hal_pwm3_ops_t fake_pwm3_ops = {
    .set_duty = fake_pwm3_set_duty,
    .enable = fake_pwm3_enable,
    .disable = fake_pwm3_disable,
    .get_state = fake_pwm3_get_state,
};

/* ---- pwm2 -------------------------------------------------------------- */

static int fake_pwm2_set_duty(void *ctx, float duty_a, float duty_b)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if (f == NULL) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_PWM2_SET_DUTY);
    if (rc != 0) {
        return rc;
    }
    if (!mc_hal_pwm2_duty_valid(duty_a) || !mc_hal_pwm2_duty_valid(duty_b)) {
        return -EINVAL;
    }
    f->pwm2.duty_a = duty_a;
    f->pwm2.duty_b = duty_b;
    return 0;
}

static int fake_pwm2_enable(void *ctx)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if (f == NULL) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_PWM2_ENABLE);
    if (rc != 0) {
        return rc;
    }
    if (f->fault.gate_killed) {
        return -EBUSY;
    }
    f->pwm2.enabled = true;
    return 0;
}

static int fake_pwm2_disable(void *ctx)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if (f == NULL) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_PWM2_DISABLE);
    if (rc != 0) {
        return rc;
    }
    f->pwm2.enabled = false;
    return 0;
}

static int fake_pwm2_get_state(void *ctx, mc_hal_pwm2_state_t *p_state)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if ((f == NULL) || (p_state == NULL)) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_PWM2_GET_STATE);
    if (rc != 0) {
        return rc;
    }
    *p_state = f->pwm2;
    return 0;
}

static const mc_hal_pwm2_ops_t fake_pwm2_ops = {
    .set_duty = fake_pwm2_set_duty,
    .enable = fake_pwm2_enable,
    .disable = fake_pwm2_disable,
    .get_state = fake_pwm2_get_state,
};

/* ---- encoder ----------------------------------------------------------- */

static int fake_encoder_read(void *ctx, mc_hal_encoder_sample_t *p_sample)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if ((f == NULL) || (p_sample == NULL)) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_ENCODER_READ);
    if (rc != 0) {
        return rc;
    }
    *p_sample = f->encoder;
    return 0;
}

static const mc_hal_encoder_ops_t fake_encoder_ops = {
    .read = fake_encoder_read,
};

/* ---- can --------------------------------------------------------------- */

static void queue_push(mc_hal_fake_can_queue_t *q, const mc_hal_can_frame_t *p)
{
    uint32_t tail = (q->head + q->count) % MC_HAL_FAKE_CAN_QUEUE_LEN;

    q->frames[tail] = *p;
    q->count++;
}

static void queue_pop(mc_hal_fake_can_queue_t *q, mc_hal_can_frame_t *p)
{
    *p = q->frames[q->head];
    q->head = (q->head + 1u) % MC_HAL_FAKE_CAN_QUEUE_LEN;
    q->count--;
}

static int fake_can_send(void *ctx, const mc_hal_can_frame_t *p_frame)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if ((f == NULL) || (p_frame == NULL)) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_CAN_SEND);
    if (rc != 0) {
        return rc;
    }
    rc = mc_hal_can_frame_check(p_frame, f->cfg.can_fd_capable);
    if (rc != 0) {
        return rc;
    }
    if (f->can_status.state == MC_HAL_CAN_STATE_BUS_OFF) {
        return -ENETDOWN;
    }
    if (f->can_tx.count >= MC_HAL_FAKE_CAN_QUEUE_LEN) {
        return -ENOBUFS;
    }
    queue_push(&f->can_tx, p_frame);
    return 0;
}

static int fake_can_receive(void *ctx, mc_hal_can_frame_t *p_frame)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if ((f == NULL) || (p_frame == NULL)) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_CAN_RECEIVE);
    if (rc != 0) {
        return rc;
    }
    if (f->can_rx.count == 0u) {
        return -EAGAIN;
    }
    queue_pop(&f->can_rx, p_frame);
    return 0;
}

static int fake_can_get_status(void *ctx, mc_hal_can_status_t *p_status)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if ((f == NULL) || (p_status == NULL)) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_CAN_GET_STATUS);
    if (rc != 0) {
        return rc;
    }
    *p_status = f->can_status;
    return 0;
}

static const mc_hal_can_ops_t fake_can_ops = {
    .send = fake_can_send,
    .receive = fake_can_receive,
    .get_status = fake_can_get_status,
};

/* ---- tick -------------------------------------------------------------- */

static int fake_tick_read(void *ctx, uint32_t *p_ticks)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if ((f == NULL) || (p_ticks == NULL)) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_TICK_READ);
    if (rc != 0) {
        return rc;
    }
    *p_ticks = f->tick_now;
    return 0;
}

static int fake_tick_get_freq_hz(void *ctx, uint32_t *p_freq_hz)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if ((f == NULL) || (p_freq_hz == NULL)) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_TICK_GET_FREQ);
    if (rc != 0) {
        return rc;
    }
    *p_freq_hz = f->cfg.tick_freq_hz;
    return 0;
}

static const mc_hal_tick_ops_t fake_tick_ops = {
    .read = fake_tick_read,
    .get_freq_hz = fake_tick_get_freq_hz,
};

/* ---- fault ------------------------------------------------------------- */

static int fake_fault_read(void *ctx, mc_hal_fault_status_t *p_status)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if ((f == NULL) || (p_status == NULL)) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_FAULT_READ);
    if (rc != 0) {
        return rc;
    }
    *p_status = f->fault;
    return 0;
}

/* No injection, no precondition: the kill does not depend on anything. */
static void fake_gate_kill(void *ctx)
{
    mc_hal_fake_t *f = ctx;

    if (f == NULL) {
        return;
    }
    f->pwm3.enabled = false;
    f->pwm2.enabled = false;
    f->fault.gate_killed = true;
    f->gate_kill_count++;
}

static int fake_gate_release(void *ctx)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if (f == NULL) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_FAULT_GATE_RELEASE);
    if (rc != 0) {
        return rc;
    }
    if (f->fault.active_mask != 0u) {
        return -EBUSY;
    }
    f->fault.gate_killed = false;
    f->fault.latched_mask = 0u;
    return 0;
}

static const mc_hal_fault_ops_t fake_fault_ops = {
    .read = fake_fault_read,
    .gate_kill = fake_gate_kill,
    .gate_release = fake_gate_release,
};

static int fake_brake_set_duty(void *ctx, float duty)
{
    mc_hal_fake_t *f = ctx;
    int rc;

    if (f == NULL) {
        return -EINVAL;
    }
    rc = fake_enter(f, MC_HAL_FAKE_BRAKE_SET_DUTY);
    if (rc != 0) {
        return rc;
    }
    if (!(duty >= 0.0f && duty <= 1.0f)) {
        return -EINVAL;
    }
    f->brake_duty = duty;
    return 0;
}

static const mc_hal_brake_ops_t fake_brake_ops = {
    .set_duty = fake_brake_set_duty,
};

/* ---- set-up and test-side controls ------------------------------------- */

int mc_hal_fake_config_default(mc_hal_fake_config_t *p_cfg)
{
    if (p_cfg == NULL) {
        return -EINVAL;
    }
    p_cfg->pwm3_period_s = 50e-6f;
    p_cfg->pwm2_period_s = 50e-6f;
    p_cfg->tick_freq_hz = 168000000u;
    p_cfg->encoder_counts_per_rev = 16384u;
    p_cfg->can_fd_capable = false;
    p_cfg->fault_input_kills = true;
    return 0;
}

int mc_hal_fake_init(mc_hal_fake_t *p_fake, const mc_hal_fake_config_t *p_cfg)
{
    if ((p_fake == NULL) || (p_cfg == NULL)) {
        return -EINVAL;
    }
    if (!period_valid(p_cfg->pwm3_period_s) || !period_valid(p_cfg->pwm2_period_s) ||
        (p_cfg->tick_freq_hz == 0u) || (p_cfg->encoder_counts_per_rev == 0u)) {
        return -EINVAL;
    }

    (void)memset(p_fake, 0, sizeof(*p_fake));
    p_fake->cfg = *p_cfg;

    p_fake->pwm3.duty_a = MC_HAL_PWM3_DUTY_INIT;
    p_fake->pwm3.duty_b = MC_HAL_PWM3_DUTY_INIT;
    p_fake->pwm3.duty_c = MC_HAL_PWM3_DUTY_INIT;
    p_fake->pwm3.period_s = p_cfg->pwm3_period_s;
    p_fake->pwm3.enabled = false;

    p_fake->pwm2.duty_a = MC_HAL_PWM2_DUTY_INIT;
    p_fake->pwm2.duty_b = MC_HAL_PWM2_DUTY_INIT;
    p_fake->pwm2.period_s = p_cfg->pwm2_period_s;
    p_fake->pwm2.enabled = false;

    p_fake->encoder.counts_per_rev = p_cfg->encoder_counts_per_rev;

    p_fake->can_status.state = MC_HAL_CAN_STATE_ERROR_ACTIVE;
    p_fake->can_status.fd_capable = p_cfg->can_fd_capable;

    p_fake->adc_dev.ops = &fake_adc_ops;
    p_fake->adc_dev.ctx = p_fake;
    p_fake->pwm3_dev.ops = &fake_pwm3_ops;
    p_fake->pwm3_dev.ctx = p_fake;
    p_fake->pwm2_dev.ops = &fake_pwm2_ops;
    p_fake->pwm2_dev.ctx = p_fake;
    p_fake->encoder_dev.ops = &fake_encoder_ops;
    p_fake->encoder_dev.ctx = p_fake;
    p_fake->can_dev.ops = &fake_can_ops;
    p_fake->can_dev.ctx = p_fake;
    p_fake->tick_dev.ops = &fake_tick_ops;
    p_fake->tick_dev.ctx = p_fake;
    p_fake->fault_dev.ops = &fake_fault_ops;
    p_fake->fault_dev.ctx = p_fake;

    p_fake->board.adc = &p_fake->adc_dev;
    p_fake->board.pwm3 = &p_fake->pwm3_dev;
    p_fake->board.pwm2 = &p_fake->pwm2_dev;
    p_fake->board.encoder = &p_fake->encoder_dev;
    p_fake->board.can = &p_fake->can_dev;
    p_fake->board.tick = &p_fake->tick_dev;
    p_fake->board.fault = &p_fake->fault_dev;
    p_fake->brake_dev.ops = &fake_brake_ops;
    p_fake->brake_dev.ctx = p_fake;
    p_fake->board.brake = &p_fake->brake_dev;
    return 0;
}

int mc_hal_fake_inject_error(mc_hal_fake_t *p_fake, mc_hal_fake_call_t call, int err,
                             uint32_t times)
{
    if ((p_fake == NULL) || ((unsigned)call >= (unsigned)MC_HAL_FAKE_CALL_COUNT) || (err >= 0)) {
        return -EINVAL;
    }
    p_fake->inject_err[call] = err;
    p_fake->inject_remaining[call] = times;
    return 0;
}

int mc_hal_fake_adc_set_sample(mc_hal_fake_t *p_fake, float ia_a, float ib_a, float ic_a,
                               float vbus_v, uint32_t valid_mask)
{
    if ((p_fake == NULL) || ((valid_mask & ~MC_HAL_ADC_VALID_ALL) != 0u)) {
        return -EINVAL;
    }
    p_fake->adc_sample.ia_a = ia_a;
    p_fake->adc_sample.ib_a = ib_a;
    p_fake->adc_sample.ic_a = ic_a;
    p_fake->adc_sample.vbus_v = vbus_v;
    p_fake->adc_sample.valid_mask = valid_mask;
    p_fake->adc_sample.timestamp_ticks = p_fake->tick_now;
    p_fake->adc_sample.seq++;
    p_fake->adc_pending = true;
    return 0;
}

int mc_hal_fake_adc_set_temp(mc_hal_fake_t *p_fake, float power_stage_temp_c, float motor_temp_c,
                             uint32_t valid_mask)
{
    if ((p_fake == NULL) || ((valid_mask & ~MC_HAL_ADC_TEMP_VALID_ALL) != 0u)) {
        return -EINVAL;
    }
    p_fake->adc_temp.power_stage_temp_c = power_stage_temp_c;
    p_fake->adc_temp.motor_temp_c = motor_temp_c;
    p_fake->adc_temp.valid_mask = valid_mask;
    return 0;
}

int mc_hal_fake_encoder_set(mc_hal_fake_t *p_fake, uint32_t count, uint32_t flags)
{
    if ((p_fake == NULL) || (count >= p_fake->encoder.counts_per_rev) ||
        ((flags & ~MC_HAL_ENCODER_FLAG_ALL) != 0u)) {
        return -EINVAL;
    }
    p_fake->encoder.count = count;
    p_fake->encoder.flags = flags;
    p_fake->encoder.timestamp_ticks = p_fake->tick_now;
    return 0;
}

int mc_hal_fake_can_rx_push(mc_hal_fake_t *p_fake, const mc_hal_can_frame_t *p_frame)
{
    mc_hal_can_frame_t frame;
    int rc;

    if ((p_fake == NULL) || (p_frame == NULL)) {
        return -EINVAL;
    }
    rc = mc_hal_can_frame_check(p_frame, p_fake->cfg.can_fd_capable);
    if (rc != 0) {
        return rc;
    }
    if (p_fake->can_rx.count >= MC_HAL_FAKE_CAN_QUEUE_LEN) {
        p_fake->can_status.rx_overrun_count++;
        return -ENOBUFS;
    }
    frame = *p_frame;
    frame.timestamp_ticks = p_fake->tick_now;
    queue_push(&p_fake->can_rx, &frame);
    return 0;
}

int mc_hal_fake_can_tx_pop(mc_hal_fake_t *p_fake, mc_hal_can_frame_t *p_frame)
{
    if ((p_fake == NULL) || (p_frame == NULL)) {
        return -EINVAL;
    }
    if (p_fake->can_tx.count == 0u) {
        return -EAGAIN;
    }
    queue_pop(&p_fake->can_tx, p_frame);
    return 0;
}

int mc_hal_fake_can_set_errors(mc_hal_fake_t *p_fake, uint16_t tx_err_count, uint16_t rx_err_count)
{
    mc_hal_can_bus_state_t state;

    if (p_fake == NULL) {
        return -EINVAL;
    }
    if (tx_err_count > 255u) {
        state = MC_HAL_CAN_STATE_BUS_OFF;
    } else if ((tx_err_count >= 128u) || (rx_err_count >= 128u)) {
        state = MC_HAL_CAN_STATE_ERROR_PASSIVE;
    } else if ((tx_err_count >= 96u) || (rx_err_count >= 96u)) {
        state = MC_HAL_CAN_STATE_ERROR_WARNING;
    } else {
        state = MC_HAL_CAN_STATE_ERROR_ACTIVE;
    }
    p_fake->can_status.tx_err_count = tx_err_count;
    p_fake->can_status.rx_err_count = rx_err_count;
    p_fake->can_status.state = state;
    return 0;
}

int mc_hal_fake_tick_advance(mc_hal_fake_t *p_fake, uint32_t ticks)
{
    if (p_fake == NULL) {
        return -EINVAL;
    }
    p_fake->tick_now += ticks; /* unsigned: wraps modulo 2^32 */
    return 0;
}

int mc_hal_fake_tick_set(mc_hal_fake_t *p_fake, uint32_t now_ticks)
{
    if (p_fake == NULL) {
        return -EINVAL;
    }
    p_fake->tick_now = now_ticks;
    return 0;
}

int mc_hal_fake_fault_set_inputs(mc_hal_fake_t *p_fake, uint32_t active_mask)
{
    if ((p_fake == NULL) || ((active_mask & ~MC_HAL_FAULT_ALL) != 0u)) {
        return -EINVAL;
    }
    p_fake->fault.active_mask = active_mask;
    p_fake->fault.latched_mask |= active_mask;
    if ((active_mask != 0u) && p_fake->cfg.fault_input_kills) {
        fake_gate_kill(p_fake);
    }
    return 0;
}
