/**
 * @file mc_hal_pil.c
 * @brief Processor-in-the-loop board: the HAL of the drive served over
 *        USART1 by the host simulator (protocol:
 *        firmware/targets/pil/mc_pil_frame.h), and the board binding of the
 *        STM32F405 image's main (firmware/targets/stm32f405/mc_board.h).
 *        Built into mc_stm32f405_pil.elf by firmware/targets/stm32f405 and
 *        tests/target (label pil).
 *
 * Runs on QEMU netduinoplus2 (USART1 is the first -serial). Each period the
 * host sends MEAS with what its simulated board's HAL returned at the sample;
 * the USART1 receive interrupt assembles the frame and pends the ADC
 * interrupt, so the fast loop runs exactly where it runs on the drive board
 * (ADC_IRQHandler in main.c); the slow loop runs in PendSV. When the period's
 * work is done, OUT goes back with the duties, the enable state and gate
 * kills the drive asked for, which the host applies to its board before it
 * integrates the period.
 *
 * The HAL ops here mirror hal_host::PmsmBoard call for call (duty check,
 * -EBUSY enable while killed, one read per ADC sample), so the drive takes
 * the same decisions as in the software-in-the-loop run.
 *
 * Two modes, chosen by the host at start-up (mc_pil_frame.h):
 *   drive alone      (CFG): mc_board_app_cfg() returns NULL, main runs the
 *                    drive on the received mc_drive_cfg_t, commands come in
 *                    MEAS (tests/target/pil/test_pil_foc.cpp);
 *   whole image      (PARAMS, APP): mc_board_app_cfg() binds the drive
 *                    application (firmware/app/app/mc_app) as the drive
 *                    boards do, with
 *       CAN          over the link: CAN_RX frames go into a receive queue
 *                    and pend CAN1_RX0, whose handler hands them to the
 *                    application (mc_main_can_rx), as bxCAN's FIFO
 *                    interrupt does on the board; every frame the
 *                    application sends leaves at once as CAN_TX, tagged
 *                    with the period. Send, receive and status answer as
 *                    the SIL's hal_host::CandumpLogCan does (no bus errors,
 *                    error-active, FD capable);
 *       flash        RAM: QEMU does not model the F405's flash controller,
 *                    so the configuration store runs on two 16 KiB sectors
 *                    of SRAM with NOR semantics (hal/fake/mc_fake_flash.c),
 *                    erased at boot, or filled with the host's FLASH
 *                    frames before APP (mcsim --pil --flash FILE: the
 *                    board's flash file, link version 6); the geometry of
 *                    the SIL's hal_host::FileFlash. A SAVE works within the
 *                    run and is gone at the next boot (the file is the
 *                    host's, never written back);
 *       watchdog     none (NULL), as in the SIL rig: QEMU's IWDG is not the
 *                    point here and a lock-step run may stall on the host;
 *       laws         from the parameters (laws_from_params), as on the
 *                    drive boards and in the SIL: speed_law picks SPEED's
 *                    law, the position law serves POSITION;
 *       commissioning over CAN as on the drive boards (mc_board_comm_cfg:
 *                    the rule of mc_comm_can_cfg_for_board from the
 *                    parameters: the table's sense range, its nominal bus
 *                    as the lowest, three shunts when current_sensors is
 *                    3; the simulator's SIL application target binds the
 *                    same);
 *       update       BOOT_REQ INFO, VERSION and the confirmed ENTER answered
 *                    from the image header (mc_image_header.h), ENTER
 *                    resetting into the bootloader through the mailbox
 *                    (mc_boot_handoff.h), as on the drive boards.
 *       stack        the main stack (stm32f405_sections.ld: MC_STACK_SIZE
 *                    bytes from _sstack, right above .bss) is painted at
 *                    start-up; after every period and at END a band of
 *                    PIL_STACK_GUARD_BYTES at its bottom must still hold the
 *                    paint, else the image exits PIL_EXIT_STACK ("stack
 *                    overflow", QEMU's exit status): an overflow writes
 *                    into the last .bss objects (this HAL's CAN receive queue)
 *                    and shows only as a SIL/PIL difference otherwise;
 *       probe        the application's probe (mc_app_probe) goes to the
 *                    host as PROBE after READY and after each period,
 *                    before OUT (link protocol version 2);
 *       brake        when APP says the board has a brake chopper
 *                    (caps MC_PIL_CAP_BRAKE), mc_hal_t.brake: the duty the
 *                    drive sets (checked as hal_host::PmsmBoard does) goes
 *                    to the host in OUT (brake_set_count, brake_duty),
 *                    which applies it to its board's brake before the
 *                    period's integration (link protocol version 3).
 *                    Without one, NULL: the application refuses
 *                    brake_enable as on the board;
 *       Hall         when APP says the board has Hall inputs (caps
 *                    MC_PIL_CAP_HALL), the Hall capability (hal/hall.h)
 *                    bound as mc_app_cfg_t.hall, as the F405 image binds
 *                    mc_f405_hall on a Hall board: its read answers the
 *                    code the host's board read at the period's sample
 *                    (MEAS hall_rc, hall_code; link protocol version 5),
 *                    and the application makes the Hall kernel on it the
 *                    drive's encoder (encoder_type 1). Without them, NULL:
 *                    the application refuses encoder_type 1 as on a board
 *                    without Hall inputs. APP with a capability this image
 *                    does not know is answered READY MC_PIL_READY_ERR_CAPS
 *                    with the image's version, so the host names it.
 *     Both loops run within the period (the ADC interrupt, then PendSV),
 *     as in the SIL's one period (hal_host::app_period): OUT carries what
 *     the bridge does in the next period.
 *
 * Emulation only: link errors, the END frame and hard faults leave through
 * ARM semihosting (exit codes below).
 */
#include <errno.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "hal/hall.h"
#include "mc_board.h"
#include "mc_boot_handoff.h"
#include "mc_cortexm.h"
#include "mc_fake_flash.h"
#include "mc_image_header.h"
#include "mc_params.h"
#include "mc_pil_frame.h"
#include "mc_pil_probe.h"
#include "mc_stm32f405.h"

/* Exit codes reported to the host through semihosting. */
#define PIL_EXIT_FRAME_ERROR  3
#define PIL_EXIT_CFG_REJECTED 2
#define PIL_EXIT_HARD_FAULT   99
#define PIL_EXIT_STACK        5 /* 4: the bootloader's "no host" */

/* The main stack's guard band (file comment, "stack"): a run whose deepest
 * path reaches the bottom 128 bytes of the 4 KiB stack fails. The
 * can-telemetry runs leave 204 bytes unused (measured by the paint at END,
 * after the anticogging calibration's frames were taken off the APPLY path);
 * the band is below that so those runs pass, and well above zero so an
 * overflow is caught before it reaches .bss. */
#define PIL_STACK_GUARD_BYTES 128u
#define PIL_STACK_PAINT       0xA5C3E1F7u

/* USART1 (RM0090 section 30.6). */
#define USART_SR             MC_REG32(MC_USART1_BASE + 0x00u)
#define USART_DR             MC_REG32(MC_USART1_BASE + 0x04u)
#define USART_BRR            MC_REG32(MC_USART1_BASE + 0x08u)
#define USART_CR1            MC_REG32(MC_USART1_BASE + 0x0Cu)
#define USART_SR_ORE         (1u << 3)
#define USART_SR_RXNE        (1u << 5)
#define USART_SR_TXE         (1u << 7)
#define USART_CR1_RE         (1u << 2)
#define USART_CR1_TE         (1u << 3)
#define USART_CR1_RXNEIE     (1u << 5)
#define USART_CR1_UE         (1u << 13)
#define RCC_APB2ENR          MC_REG32(MC_RCC_BASE + MC_RCC_APB2ENR_OFS)
#define RCC_APB2ENR_USART1EN (1u << 4)
#define PIL_BAUD             115200u

#define PRIO_LINK_RX 1u
#define PRIO_CAN_RX  8u /* as the drive board's CAN1_RX0 */

/* The configuration store's RAM flash: hal_host::FileFlash's geometry. */
#define PIL_FLASH_SECTORS      2u
#define PIL_FLASH_SECTOR_BYTES (16u * 1024u)
/* Received CAN frames not yet taken by the application (a power of two). */
#define PIL_CAN_RX_LEN 64u

void USART1_IRQHandler(void);
void CAN1_RX0_IRQHandler(void);
void HardFault_Handler(void);

/* What the drive did to the bridge in a part of the period. */
typedef struct {
    uint32_t duty_set_count;
    float duty[3]; /**< last accepted duties */
    bool pwm_enabled;
    uint32_t gate_kill_count;
} pil_bridge_t;

typedef struct {
    /* link */
    uint8_t rx[MC_PIL_MAX_FRAME];
    size_t rx_len;
    mc_pil_meas_t meas; /**< the period's measurements */
    bool meas_pending;  /**< commands of meas not applied yet */
    bool adc_fresh;     /**< meas.adc not read yet */
    uint32_t sysclk_hz;
    mc_drive_cfg_t cfg;
    bool have_cfg;
    /* bridge mirror */
    float duty[3];
    bool pwm_enabled;
    bool killed_here; /**< gate kill by the drive (host kill is in meas) */
    uint32_t duty_set_count;
    uint32_t gate_kill_count;
    float brake_duty;
    uint32_t brake_set_count;
    int32_t cmd_rc;
    uint32_t ipsr_fast;
    /* HAL handles */
    mc_hal_adc_t adc;
    mc_hal_pwm3_t pwm3;
    mc_hal_encoder_t enc;
    mc_hal_tick_t tick;
    mc_hal_fault_t fault;
    mc_hal_can_t can;
    mc_hal_brake_t brake;
    mc_hal_hall_t hall;
    mc_hal_t hal;
    /* whole-image mode */
    bool app_mode;
    bool have_app;
    mc_params_t defaults;
    mc_app_cfg_t app;
    mc_fake_flash_t flash;
    /* CAN receive queue: written by the link interrupt, read by CAN1_RX0 */
    mc_hal_can_frame_t can_rx[PIL_CAN_RX_LEN];
    uint32_t can_rx_head;
    uint32_t can_rx_tail;
    uint32_t can_rx_overruns;
} pil_board_t;

static pil_board_t g_pil;
static uint8_t g_flash_mem[PIL_FLASH_SECTORS * PIL_FLASH_SECTOR_BYTES];

/* ---- semihosting (emulation only) -------------------------------------- */

#if defined(__arm__)
static void sh_call(uint32_t op, const void *arg)
{
    register uint32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
}
#else
static void sh_call(uint32_t op, const void *arg)
{
    (void)op;
    (void)arg;
}
#endif

static void sh_write0(const char *s)
{
    sh_call(0x04u, s);
}

static void sh_exit(int code) __attribute__((noreturn));
static void sh_exit(int code)
{
    /* SYS_EXIT_EXTENDED, ADP_Stopped_ApplicationExit with the code. */
    static uint32_t block[2];
    block[0] = 0x20026u;
    block[1] = (uint32_t)code;
    sh_call(0x20u, block);
    for (;;) {
        mc_wfi();
    }
}

/* ---- the main stack's guard (file comment, "stack") --------------------- */

#if defined(__arm__)
extern uint32_t _sstack[]; /* the linker script's: the stack's lowest word */

/* Paint from the stack's bottom up to 64 bytes below this frame. */
static void stack_paint(void)
{
    volatile uint32_t here = 0u;
    const uintptr_t top = (uintptr_t)&here - 64u;
    for (uint32_t *w = _sstack; (uintptr_t)w < top; ++w) {
        *w = PIL_STACK_PAINT;
    }
}

/* The guard band still holds the paint. */
static bool stack_guard_intact(void)
{
    const volatile uint32_t *w = _sstack;
    for (uint32_t k = 0u; k < PIL_STACK_GUARD_BYTES / 4u; ++k) {
        if (w[k] != PIL_STACK_PAINT) {
            return false;
        }
    }
    return true;
}

/* Exit PIL_EXIT_STACK when the guard band was written: at once, so the
 * host's link reports the image's exit instead of the damage it did. */
static void stack_check(void)
{
    if (!stack_guard_intact()) {
        sh_write0("pil: stack overflow (the main stack reached its guard band)\n");
        sh_exit(PIL_EXIT_STACK);
    }
}
#else
/* the host's build of this file (lint): no stack to guard */
static void stack_paint(void)
{
}

static void stack_check(void)
{
}
#endif

void HardFault_Handler(void)
{
    sh_write0("pil: hard fault\n");
    sh_exit(PIL_EXIT_HARD_FAULT);
}

/* ---- USART1 ------------------------------------------------------------ */

static void usart_send(const uint8_t *p, size_t n)
{
    for (size_t i = 0u; i < n; ++i) {
        while ((USART_SR & USART_SR_TXE) == 0u) {
        }
        USART_DR = p[i];
    }
}

/* Add one received byte; returns the frame type once a whole frame is in
 * g_pil.rx (0 while incomplete). Exits on a corrupt frame: the link is a
 * lossless emulated wire, so an error means a protocol bug. */
static int rx_byte(uint8_t b)
{
    if (g_pil.rx_len == 0u && b != MC_PIL_SYNC) {
        sh_write0("pil: lost frame sync\n");
        sh_exit(PIL_EXIT_FRAME_ERROR);
    }
    g_pil.rx[g_pil.rx_len] = b;
    g_pil.rx_len++;
    const size_t want = mc_pil_frame_len(g_pil.rx, g_pil.rx_len);
    if (want == 0u || g_pil.rx_len < want) {
        return 0;
    }
    const int type = mc_pil_frame_type(g_pil.rx, g_pil.rx_len);
    if (type < 0) {
        sh_write0("pil: bad frame (CRC or length)\n");
        sh_exit(PIL_EXIT_FRAME_ERROR);
    }
    return type;
}

static void handle_frame(int type)
{
    const size_t n = g_pil.rx_len;
    g_pil.rx_len = 0u;
    if (type == (int)MC_PIL_TYPE_MEAS) {
        if (mc_pil_decode_meas(g_pil.rx, n, &g_pil.meas) != MC_PIL_OK) {
            sh_exit(PIL_EXIT_FRAME_ERROR);
        }
        g_pil.meas_pending = true;
        g_pil.adc_fresh = true;
        /* The conversion is "complete": run the fast loop as the ADC would. */
        mc_nvic_set_pending(MC_IRQ_ADC);
    } else if (type == (int)MC_PIL_TYPE_CAN_RX && g_pil.app_mode) {
        mc_hal_can_frame_t f;
        if (mc_pil_decode_can_rx(g_pil.rx, n, &f) != MC_PIL_OK) {
            sh_exit(PIL_EXIT_FRAME_ERROR);
        }
        if (g_pil.can_rx_tail - g_pil.can_rx_head < PIL_CAN_RX_LEN) {
            g_pil.can_rx[g_pil.can_rx_tail % PIL_CAN_RX_LEN] = f;
            __atomic_store_n(&g_pil.can_rx_tail, g_pil.can_rx_tail + 1u, __ATOMIC_RELEASE);
        } else {
            g_pil.can_rx_overruns++; /* as a full FIFO: counted, reported by status */
        }
        mc_nvic_set_pending(MC_IRQ_CAN1_RX0);
    } else if (type == (int)MC_PIL_TYPE_END) {
        int32_t code = 0;
        (void)mc_pil_decode_end(g_pil.rx, n, &code);
        stack_check();
        sh_exit((int)code);
    } else {
        sh_write0("pil: unexpected frame type\n");
        sh_exit(PIL_EXIT_FRAME_ERROR);
    }
}

void USART1_IRQHandler(void)
{
    while ((USART_SR & (USART_SR_RXNE | USART_SR_ORE)) != 0u) {
        const int type = rx_byte((uint8_t)(USART_DR & 0xFFu));
        if (type > 0) {
            handle_frame(type);
        }
    }
}

/* ---- HAL ops ----------------------------------------------------------- */

static int adc_read(void *ctx, mc_hal_adc_sample_t *p_sample)
{
    pil_board_t *b = ctx;
    if (!b->adc_fresh) {
        return -EAGAIN;
    }
    b->adc_fresh = false;
    if (b->meas.adc_rc != 0) {
        return (int)b->meas.adc_rc;
    }
    *p_sample = b->meas.adc;
    return 0;
}

static int adc_read_temp(void *ctx, mc_hal_adc_temp_t *p_temp)
{
    const pil_board_t *b = ctx;
    if (b->meas.temp_rc != 0) {
        return (int)b->meas.temp_rc;
    }
    *p_temp = b->meas.temp;
    return 0;
}

static int pwm_set_duty(void *ctx, float da, float db, float dc)
{
    pil_board_t *b = ctx;
    if (!mc_hal_pwm3_duty_valid(da) || !mc_hal_pwm3_duty_valid(db) || !mc_hal_pwm3_duty_valid(dc)) {
        return -EINVAL;
    }
    b->duty[0] = da;
    b->duty[1] = db;
    b->duty[2] = dc;
    b->duty_set_count++;
    return 0;
}

/* As hal_host::PmsmBoard::brake_set_duty: NaN or outside [0, 1] refused. */
static int brake_set_duty(void *ctx, float duty)
{
    pil_board_t *b = ctx;
    if (!((duty >= 0.0f) && (duty <= 1.0f))) {
        return -EINVAL;
    }
    b->brake_duty = duty;
    b->brake_set_count++;
    return 0;
}

/* The code the host's board read at the sample; a code outside the three
 * bits is a host bug, answered -EIO (the drive faults ENCODER). */
static int hall_read(void *ctx, uint32_t *p_code)
{
    const pil_board_t *b = ctx;
    if (b->meas.hall_rc != 0) {
        return (int)b->meas.hall_rc;
    }
    if (b->meas.hall_code > 7u) {
        return -EIO;
    }
    *p_code = b->meas.hall_code;
    return 0;
}

static bool gate_killed(const pil_board_t *b)
{
    return b->killed_here || b->meas.fault.gate_killed;
}

static int pwm_enable(void *ctx)
{
    pil_board_t *b = ctx;
    if (gate_killed(b)) {
        return -EBUSY;
    }
    b->pwm_enabled = true;
    return 0;
}

static int pwm_disable(void *ctx)
{
    pil_board_t *b = ctx;
    b->pwm_enabled = false;
    return 0;
}

static int pwm_get_state(void *ctx, mc_hal_pwm3_state_t *p_state)
{
    const pil_board_t *b = ctx;
    p_state->duty_a = b->duty[0];
    p_state->duty_b = b->duty[1];
    p_state->duty_c = b->duty[2];
    p_state->period_s = b->cfg.foc.dt_s;
    p_state->enabled = b->pwm_enabled && !gate_killed(b);
    return 0;
}

static int enc_read(void *ctx, mc_hal_encoder_sample_t *p_sample)
{
    const pil_board_t *b = ctx;
    if (b->meas.enc_rc != 0) {
        return (int)b->meas.enc_rc;
    }
    *p_sample = b->meas.enc;
    return 0;
}

static int tick_read(void *ctx, uint32_t *p_ticks)
{
    const pil_board_t *b = ctx;
    *p_ticks = b->meas.tick_ticks;
    return 0;
}

static int tick_freq(void *ctx, uint32_t *p_hz)
{
    const pil_board_t *b = ctx;
    *p_hz = b->meas.tick_hz;
    return 0;
}

static int fault_read(void *ctx, mc_hal_fault_status_t *p_status)
{
    const pil_board_t *b = ctx;
    if (b->meas.fault_rc != 0) {
        return (int)b->meas.fault_rc;
    }
    *p_status = b->meas.fault;
    p_status->gate_killed = gate_killed(b);
    return 0;
}

static void fault_gate_kill(void *ctx)
{
    pil_board_t *b = ctx;
    b->killed_here = true;
    b->gate_kill_count++;
}

/* Releasing the kill is not part of the PIL protocol (no scenario clears
 * faults over the link), so it is refused as a latched kill would be. */
static int fault_gate_release(void *ctx)
{
    (void)ctx;
    return -EBUSY;
}

/* CAN over the link: answers as hal_host::CandumpLogCan (the SIL's). */
static int can_send(void *ctx, const mc_hal_can_frame_t *p_frame)
{
    const pil_board_t *b = ctx;
    const int rc = mc_hal_can_frame_check(p_frame, true);
    if (rc != 0) {
        return rc;
    }
    uint8_t buf[MC_PIL_MAX_FRAME] = {0u};
    usart_send(buf, mc_pil_encode_can_tx(b->meas.seq, p_frame, buf, sizeof buf));
    return 0;
}

static int can_receive(void *ctx, mc_hal_can_frame_t *p_frame)
{
    pil_board_t *b = ctx;
    const uint32_t tail = __atomic_load_n(&b->can_rx_tail, __ATOMIC_ACQUIRE);
    if (tail == b->can_rx_head) {
        return -EAGAIN;
    }
    *p_frame = b->can_rx[b->can_rx_head % PIL_CAN_RX_LEN];
    __atomic_store_n(&b->can_rx_head, b->can_rx_head + 1u, __ATOMIC_RELEASE);
    return 0;
}

static int can_get_status(void *ctx, mc_hal_can_status_t *p_status)
{
    const pil_board_t *b = ctx;
    memset(p_status, 0, sizeof *p_status);
    p_status->state = MC_HAL_CAN_STATE_ERROR_ACTIVE;
    p_status->rx_overrun_count = b->can_rx_overruns;
    p_status->fd_capable = true;
    return 0;
}

void CAN1_RX0_IRQHandler(void)
{
    mc_main_can_rx();
}

static const mc_hal_can_ops_t k_can_ops = {can_send, can_receive, can_get_status};
static const mc_hal_adc_ops_t k_adc_ops = {adc_read, adc_read_temp};
static const mc_hal_pwm3_ops_t k_pwm3_ops = {pwm_set_duty, pwm_enable, pwm_disable, pwm_get_state};
static const mc_hal_encoder_ops_t k_enc_ops = {enc_read};
static const mc_hal_tick_ops_t k_tick_ops = {tick_read, tick_freq};
static const mc_hal_fault_ops_t k_fault_ops = {fault_read, fault_gate_kill, fault_gate_release};
static const mc_hal_brake_ops_t k_brake_ops = {brake_set_duty};
static const mc_hal_hall_ops_t k_hall_ops = {hall_read};

/* ---- mc_board.h -------------------------------------------------------- */

const mc_hal_t *mc_board_init(uint32_t sysclk_hz)
{
    stack_paint();
    memset(&g_pil, 0, sizeof g_pil);
    g_pil.sysclk_hz = sysclk_hz;
    g_pil.duty[0] = MC_HAL_PWM3_DUTY_INIT;
    g_pil.duty[1] = MC_HAL_PWM3_DUTY_INIT;
    g_pil.duty[2] = MC_HAL_PWM3_DUTY_INIT;
    g_pil.adc = (mc_hal_adc_t){&k_adc_ops, &g_pil};
    g_pil.pwm3 = (mc_hal_pwm3_t){&k_pwm3_ops, &g_pil};
    g_pil.enc = (mc_hal_encoder_t){&k_enc_ops, &g_pil};
    g_pil.tick = (mc_hal_tick_t){&k_tick_ops, &g_pil};
    g_pil.fault = (mc_hal_fault_t){&k_fault_ops, &g_pil};
    g_pil.hal.adc = &g_pil.adc;
    g_pil.hal.pwm3 = &g_pil.pwm3;
    g_pil.hal.pwm2 = NULL;
    g_pil.hal.encoder = &g_pil.enc;
    g_pil.can = (mc_hal_can_t){&k_can_ops, &g_pil};
    g_pil.hal.can = NULL; /* set in the whole-image mode */
    g_pil.hal.tick = &g_pil.tick;
    g_pil.hal.fault = &g_pil.fault;
    g_pil.brake = (mc_hal_brake_t){&k_brake_ops, &g_pil};
    g_pil.hal.brake = NULL; /* set in the whole-image mode when the board has one */
    g_pil.hall = (mc_hal_hall_t){&k_hall_ops, &g_pil}; /* bound by APP's caps */

    /* USART1 on APB2 (84 MHz on silicon; QEMU ignores the rate). */
    RCC_APB2ENR |= RCC_APB2ENR_USART1EN;
    const uint32_t pclk2_hz = (sysclk_hz != 0u) ? sysclk_hz / 2u : 84000000u;
    USART_BRR = (pclk2_hz + PIL_BAUD / 2u) / PIL_BAUD;
    USART_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE;
    return &g_pil.hal;
}

/* Receive one whole frame by polling (before interrupts run). */
static int poll_frame(void)
{
    for (;;) {
        if ((USART_SR & USART_SR_RXNE) == 0u) {
            continue;
        }
        const int type = rx_byte((uint8_t)(USART_DR & 0xFFu));
        if (type != 0) {
            return type;
        }
    }
}

static void setup_fail(const char *what)
{
    sh_write0(what);
    sh_exit(PIL_EXIT_FRAME_ERROR);
}

static void send_ready(uint32_t err);

/* A FLASH frame's bytes into the RAM store (its offset and length checked
 * against the store: the frame's own buffer, nothing on the stack). */
static void receive_flash(void)
{
    uint32_t off = 0u;
    uint32_t n = 0u;
    const uint8_t *data = NULL;
    if (mc_pil_decode_flash(g_pil.rx, g_pil.rx_len, &off, &data, &n) != MC_PIL_OK) {
        setup_fail("pil: bad FLASH frame\n");
    }
    if ((off > sizeof g_flash_mem) || (n > sizeof g_flash_mem - off)) {
        setup_fail("pil: FLASH beyond the store's two sectors\n");
    }
    memcpy(&g_flash_mem[off], data, n);
}

/* Whole-image mode: PARAMS frames onto the table's defaults and FLASH
 * frames into the erased RAM store, then APP. */
static void receive_app_setup(int type)
{
    uint32_t ids[MC_PIL_PARAMS_MAX];
    uint32_t raws[MC_PIL_PARAMS_MAX];
    g_pil.defaults = mc_params_default;
    /* An erased flash, as a new FileFlash file, until FLASH frames fill it. */
    memset(g_flash_mem, 0xFF, sizeof g_flash_mem);
    while ((type == (int)MC_PIL_TYPE_PARAMS) || (type == (int)MC_PIL_TYPE_FLASH)) {
        uint32_t n = 0u;
        if (type == (int)MC_PIL_TYPE_FLASH) {
            receive_flash();
            g_pil.rx_len = 0u;
            type = poll_frame();
            continue;
        }
        if (mc_pil_decode_params(g_pil.rx, g_pil.rx_len, ids, raws, &n) != MC_PIL_OK) {
            setup_fail("pil: bad PARAMS frame\n");
        }
        for (uint32_t i = 0u; i < n; ++i) {
            const mc_param_info_t *info = mc_param_find(ids[i], NULL);
            if (info == NULL || mc_param_check_value(info, raws[i]) != MC_PARAM_OK) {
                setup_fail("pil: unknown parameter or value out of range\n");
            }
            mc_param_set_raw(&g_pil.defaults, info, raws[i]);
        }
        g_pil.rx_len = 0u;
        type = poll_frame();
    }
    mc_pil_app_t a;
    if (type != (int)MC_PIL_TYPE_APP ||
        mc_pil_decode_app(g_pil.rx, g_pil.rx_len, &a) != MC_PIL_OK) {
        setup_fail("pil: expected an APP frame\n");
    }
    g_pil.rx_len = 0u;
    if ((a.caps & ~MC_PIL_CAP_ALL) != 0u) {
        /* a host of another version: READY with this image's version, so
         * the host names the mismatch */
        send_ready(MC_PIL_READY_ERR_CAPS);
        setup_fail("pil: APP names a capability this image does not have\n");
    }

    mc_app_cfg_t *c = &g_pil.app;
    memset(c, 0, sizeof *c);
    c->defaults = &g_pil.defaults;
    c->tm_budget_frac = a.tm_budget_frac;
    _Static_assert(sizeof c->tm_ext_rate_hz / sizeof c->tm_ext_rate_hz[0] == MC_PIL_TM_EXT_RATES,
                   "the APP frame carries every rate past POSITION");
    for (uint32_t i = 0u; i < MC_PIL_TM_EXT_RATES; ++i) {
        c->tm_ext_rate_hz[i] = (uint16_t)a.tm_ext_rate_hz[i];
    }
    c->pwm_hz_fixed = a.pwm_hz_fixed;
    c->slow_loop_div_fixed = a.slow_loop_div_fixed;
    /* The laws of SPEED and POSITION from the parameters, as on the drive
     * boards and in the SIL's can-telemetry. */
    c->laws_from_params = true;
    /* The tick counter's rate before the first period (mc_drive_init reads
     * it for the control deadline); each MEAS brings it again. */
    g_pil.meas.tick_hz = a.tick_hz;
    /* The RAM store: erased, or the host's FLASH content (the board's file) */
    static const uint32_t sector_bytes[PIL_FLASH_SECTORS] = {PIL_FLASH_SECTOR_BYTES,
                                                             PIL_FLASH_SECTOR_BYTES};
    if (mc_fake_flash_init(&g_pil.flash, g_flash_mem, sector_bytes, PIL_FLASH_SECTORS) == 0) {
        c->flash = &g_pil.flash.dev;
        c->flash_sectors[0] = 0u;
        c->flash_sectors[1] = 1u;
    }
    c->wdg = NULL;
    c->set_rx_filter = NULL;
    c->boot = &mc_image_boot_cfg;
    c->enter_boot = mc_boot_mailbox_enter; /* frames are sent at once: nothing to drain */
    c->boot_ctx = NULL;
    g_pil.hal.can = &g_pil.can;
    g_pil.hal.brake = ((a.caps & MC_PIL_CAP_BRAKE) != 0u) ? &g_pil.brake : NULL;
    /* the drive's encoder is the Hall kernel on them (mc_app), as the F405
     * image binds mc_f405_hall on a Hall board */
    c->hall = ((a.caps & MC_PIL_CAP_HALL) != 0u) ? &g_pil.hall : NULL;
    g_pil.app_mode = true;
    g_pil.have_app = true;
}

/* Tell the host the receiver is on (mc_board_init), then, before
 * interrupts, poll for the set-up: CFG (drive alone) or PARAMS/APP. */
static void handshake(void)
{
    static bool done;
    if (done) {
        return;
    }
    done = true;
    uint8_t hello[MC_PIL_HEADER_LEN + MC_PIL_CRC_LEN] = {0u};
    usart_send(hello, mc_pil_encode_hello(hello, sizeof hello));
    const int type = poll_frame();
    if (type == (int)MC_PIL_TYPE_CFG) {
        if (mc_pil_decode_cfg(g_pil.rx, g_pil.rx_len, &g_pil.cfg) != MC_PIL_OK) {
            setup_fail("pil: bad CFG frame\n");
        }
        g_pil.rx_len = 0u;
        g_pil.have_cfg = true;
        return;
    }
    if (type == (int)MC_PIL_TYPE_PARAMS || type == (int)MC_PIL_TYPE_FLASH ||
        type == (int)MC_PIL_TYPE_APP) {
        receive_app_setup(type);
        return;
    }
    setup_fail("pil: expected a CFG, PARAMS or APP frame\n");
}

const mc_app_cfg_t *mc_board_app_cfg(void)
{
    handshake();
    return g_pil.have_app ? &g_pil.app : NULL;
}

const mc_comm_can_cfg_t *mc_board_comm_cfg(const mc_params_t *p)
{
    static mc_comm_can_cfg_t comm;
    mc_comm_can_cfg_for_board(p, p->i_sense_max_a, p->vbus_v, p->current_sensors == 3u, &comm);
    return &comm;
}

const mc_drive_cfg_t *mc_board_drive_cfg(void)
{
    handshake();
    return g_pil.have_cfg ? &g_pil.cfg : NULL;
}

static void send_ready(uint32_t err)
{
    uint8_t buf[MC_PIL_MAX_FRAME];
    const mc_pil_ready_t r = {err, g_pil.sysclk_hz, MC_PIL_VERSION};
    const size_t n = mc_pil_encode_ready(&r, buf, sizeof buf);
    usart_send(buf, n);
}

/* Whole-image mode: the application's probe to the host (PROBE, PROBE2). */
static void send_probe(void)
{
    const mc_app_t *app = mc_main_app();
    if (!g_pil.app_mode || (app == NULL)) {
        return;
    }
    mc_app_probe_t p;
    mc_app_probe(app, &p);
    uint8_t buf[MC_PIL_MAX_FRAME] = {0u};
    usart_send(buf, mc_pil_encode_probe(&p, buf, sizeof buf));
    usart_send(buf, mc_pil_encode_probe2(&p, buf, sizeof buf));
}

void mc_board_start(void)
{
    /* Receive interrupt on before READY goes out: the host answers READY
     * with the first MEAS at once. QEMU 7.2's USART does not raise its
     * interrupt when RXNEIE is set while RXNE already is (silicon does), so
     * a byte that came early is handed to the interrupt by hand. */
    mc_nvic_set_priority(MC_IRQ_USART1, PRIO_LINK_RX);
    USART_CR1 |= USART_CR1_RXNEIE;
    mc_nvic_enable(MC_IRQ_USART1);
    if (g_pil.app_mode) {
        mc_nvic_set_priority(MC_IRQ_CAN1_RX0, PRIO_CAN_RX);
        mc_nvic_enable(MC_IRQ_CAN1_RX0);
    }
    if ((USART_SR & USART_SR_RXNE) != 0u) {
        mc_nvic_set_pending(MC_IRQ_USART1);
    }
    send_ready(MC_DRIVE_CFG_OK);
    send_probe(); /* the application after boot */
}

void mc_board_fast_irq_ack(void)
{
    /* Software-pended: the NVIC cleared the pending bit on entry. */
}

void mc_board_apply_commands(mc_drive_t *d)
{
    g_pil.ipsr_fast = mc_ipsr();
    g_pil.cmd_rc = 0;
    if (!g_pil.meas_pending) {
        return;
    }
    g_pil.meas_pending = false;
    int rc = 0;
    if ((g_pil.meas.cmd_flags & MC_PIL_CMD_SET_MODE) != 0u) {
        rc = mc_drive_set_mode(d, (mc_drive_mode_t)g_pil.meas.mode);
    }
    if ((g_pil.meas.cmd_flags & MC_PIL_CMD_SET_REFS) != 0u) {
        const int rc2 = mc_drive_set_current_ref(d, g_pil.meas.id_ref_a, g_pil.meas.iq_ref_a);
        if (rc == 0) {
            rc = rc2;
        }
    }
    g_pil.cmd_rc = (int32_t)rc;
}

static pil_bridge_t bridge_now(void)
{
    pil_bridge_t b;
    b.duty_set_count = g_pil.duty_set_count;
    b.duty[0] = g_pil.duty[0];
    b.duty[1] = g_pil.duty[1];
    b.duty[2] = g_pil.duty[2];
    b.pwm_enabled = g_pil.pwm_enabled;
    b.gate_kill_count = g_pil.gate_kill_count;
    return b;
}

void mc_board_period_done(const mc_drive_t *d, bool slow_ran)
{
    mc_pil_out_t o;
    stack_check();
    const pil_bridge_t now = bridge_now();
    const pil_bridge_t *drv = &now;
    o.seq = g_pil.meas.seq;
    o.duty_set_count = drv->duty_set_count;
    o.duty_a = drv->duty[0];
    o.duty_b = drv->duty[1];
    o.duty_c = drv->duty[2];
    o.pwm_enabled = drv->pwm_enabled ? 1u : 0u;
    o.gate_kill_count = drv->gate_kill_count;
    o.cmd_rc = g_pil.cmd_rc;
    o.mode = (uint32_t)d->mode;
    o.faults = d->faults;
    o.first_fault = d->first_fault;
    o.foc_err = d->foc_err;
    o.id_a = d->tm.foc.id_a;
    o.iq_a = d->tm.foc.iq_a;
    o.vd_v = d->tm.foc.vd_v;
    o.vq_v = d->tm.foc.vq_v;
    o.theta_e_rad = d->tm.theta_e_rad;
    o.omega_m_rad_s = d->tm.omega_m_rad_s;
    o.ipsr_fast = g_pil.ipsr_fast;
    o.ipsr_slow = slow_ran ? mc_ipsr() : 0u;
    o.slow_ran = slow_ran ? 1u : 0u;
    o.brake_set_count = g_pil.brake_set_count;
    o.brake_duty = g_pil.brake_duty;
    g_pil.brake_set_count = 0u;
    g_pil.duty_set_count = 0u;
    g_pil.gate_kill_count = 0u;

    send_probe();
    uint8_t buf[MC_PIL_MAX_FRAME];
    const size_t n = mc_pil_encode_out(&o, buf, sizeof buf);
    usart_send(buf, n);
}

void mc_board_halt(uint32_t drive_cfg_err)
{
    send_ready(drive_cfg_err);
    sh_write0("pil: drive configuration rejected\n");
    sh_exit(PIL_EXIT_CFG_REJECTED);
}
