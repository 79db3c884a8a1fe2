/**
 * @file mc_f405_iwdg.h
 * @brief STM32F405 independent watchdog (RM0090 section 19, IWDG) and the
 *        reset flags of RCC_CSR (RM0090 section 7.3.21): the hal/wdg.h
 *        contract at register level.
 *
 * IWDG: a 12-bit down-counter clocked by the LSI (32 kHz nominal, 17..47 kHz
 * over the device's range, DS8626 table "LSI oscillator characteristics")
 * through a prescaler /4 .. /256 (PR = 0..6). Key register: 0xCCCC starts the
 * watchdog (and the LSI), 0x5555 unlocks PR and RLR, 0xAAAA reloads the
 * counter from RLR (a feed). A write to PR or RLR takes effect after up to
 * five LSI periods; SR.PVU / SR.RVU are set meanwhile and a new value must
 * not be written before they clear. The timeout is
 *     t = 4 * 2^PR * (RLR + 1) / f_LSI,
 * and this driver picks the smallest prescaler whose RLR fits 12 bits for
 * at least the requested time at the nominal 32 kHz (the real timeout is
 * then t * 32 kHz / f_LSI: 0.68 .. 1.88 times the nominal one).
 *
 * RCC_CSR reset flags (bits 24..31): RMVF (write 1: clear the flags),
 * BORRSTF, PINRSTF, PORRSTF, SFTRSTF, IWDGRSTF, WWDGRSTF, LPWRRSTF. A
 * power-on sets PORRSTF, BORRSTF and PINRSTF (the reset value of RCC_CSR is
 * 0x0E000000); a brown-out alone sets BORRSTF and PINRSTF; the internal
 * resets also drive NRST, so PINRSTF accompanies every cause. The driver
 * latches the flags at init and clears them (RMVF), so the next boot sees
 * only its own reset. Decoding: MC_HAL_WDG_RESET_BROWNOUT only when BORRSTF
 * is set without PORRSTF; MC_HAL_WDG_RESET_PIN only when PINRSTF is the only
 * flag (an external NRST pulse).
 *
 * Like the other drivers it reaches the hardware only through pointers in
 * its config, so the host test runs it against RAM (the emulated MCU maps
 * neither block: its reads return 0, i.e. SR ready and no reset flag).
 */
#ifndef MC_F405_IWDG_H
#define MC_F405_IWDG_H

#include <stdint.h>

#include "hal/wdg.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_F405_IWDG_BASE    0x40003000u /**< IWDG registers */
#define MC_F405_RCC_CSR_ADDR 0x40023874u /**< RCC base 0x40023800 + 0x74 */

#define MC_F405_IWDG_KEY_RELOAD 0xAAAAu
#define MC_F405_IWDG_KEY_UNLOCK 0x5555u
#define MC_F405_IWDG_KEY_START  0xCCCCu
#define MC_F405_IWDG_SR_PVU     (1u << 0)
#define MC_F405_IWDG_SR_RVU     (1u << 1)
#define MC_F405_IWDG_RLR_MAX    0xFFFu
#define MC_F405_IWDG_PR_MAX     6u      /**< /256 */
#define MC_F405_IWDG_LSI_HZ     32000u  /**< nominal LSI */
#define MC_F405_IWDG_SR_POLLS   100000u /**< polls of SR before -EIO */

#define MC_F405_RCC_CSR_RMVF     (1u << 24)
#define MC_F405_RCC_CSR_BORRSTF  (1u << 25)
#define MC_F405_RCC_CSR_PINRSTF  (1u << 26)
#define MC_F405_RCC_CSR_PORRSTF  (1u << 27)
#define MC_F405_RCC_CSR_SFTRSTF  (1u << 28)
#define MC_F405_RCC_CSR_IWDGRSTF (1u << 29)
#define MC_F405_RCC_CSR_WWDGRSTF (1u << 30)
#define MC_F405_RCC_CSR_LPWRRSTF (1u << 31)

typedef struct mc_f405_iwdg_regs {
    volatile uint32_t KR;  /* 0x00 key (write only) */
    volatile uint32_t PR;  /* 0x04 prescaler, 3 bits */
    volatile uint32_t RLR; /* 0x08 reload, 12 bits */
    volatile uint32_t SR;  /* 0x0C PVU, RVU */
} mc_f405_iwdg_regs_t;

typedef struct mc_f405_iwdg_config {
    mc_f405_iwdg_regs_t *p_iwdg;
    volatile uint32_t *p_rcc_csr;
    /** Test hook (NULL on the MCU): called in every SR poll, so a host test
     *  can model the peripheral clearing PVU/RVU. */
    void (*hw_poll)(void *ctx);
    void *hw_ctx;
} mc_f405_iwdg_config_t;

typedef struct mc_f405_iwdg {
    mc_f405_iwdg_config_t cfg;
    uint32_t csr_at_boot; /**< RCC_CSR as read at init (flags before RMVF) */
    uint32_t cause;       /**< MC_HAL_WDG_RESET_* decoded from it */
    uint32_t timeout_ms;  /**< nominal timeout in force (0: not started) */
    mc_hal_wdg_t dev;
} mc_f405_iwdg_t;

/** Prescaler code and reload value for a timeout at the nominal LSI:
 *  smallest PR with RLR + 1 = ceil(timeout_ms f_LSI / (1000 * 4 * 2^PR))
 *  <= 4096. @return 0; -EINVAL timeout 0 or beyond PR 6 / RLR 0xFFF. */
int mc_f405_iwdg_divider(uint32_t timeout_ms, uint32_t *p_pr, uint32_t *p_rlr);

/** RCC_CSR flags -> MC_HAL_WDG_RESET_* bits (see the file comment). */
uint32_t mc_f405_reset_cause_decode(uint32_t csr);

/** Latch and clear the reset flags; the watchdog is not started (that is
 *  mc_hal_wdg_start on p_drv->dev). @return 0; -EINVAL NULL pointer. */
int mc_f405_iwdg_init(mc_f405_iwdg_t *p_drv, const mc_f405_iwdg_config_t *p_cfg);

#ifdef __cplusplus
}
#endif

#endif /* MC_F405_IWDG_H */
