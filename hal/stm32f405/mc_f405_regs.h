/**
 * @file mc_f405_regs.h
 * @brief STM32F405 register maps used by the register-level HAL: timers,
 *        ADC, bxCAN, SPI, GPIO. Written from the reference manual RM0090
 *        (STM32F405/415/407/417/427/437/429/439); no vendor header.
 *
 * Each peripheral is a struct of 32-bit volatile registers whose layout is
 * checked against the RM0090 offsets by static assertions below. The drivers
 * take a pointer to such a struct in their config: on the MCU it is the
 * peripheral's base address (MC_F405_TIM1 ...), on the host a struct in RAM
 * (a "register file") that a test inspects and pokes.
 *
 * Only the fields and bits the drivers use are named. Section numbers refer
 * to RM0090 (Rev 19); register maps are at the end of each chapter.
 */
#ifndef MC_F405_REGS_H
#define MC_F405_REGS_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Memory map (RM0090 §2.3, Table 1) -------------------------------- */

#define MC_F405_TIM2_BASE       0x40000000u /* APB1 */
#define MC_F405_TIM3_BASE       0x40000400u
#define MC_F405_TIM4_BASE       0x40000800u
#define MC_F405_TIM5_BASE       0x40000C00u
#define MC_F405_CAN1_BASE       0x40006400u
#define MC_F405_CAN2_BASE       0x40006800u
#define MC_F405_TIM1_BASE       0x40010000u /* APB2 */
#define MC_F405_TIM8_BASE       0x40010400u
#define MC_F405_ADC1_BASE       0x40012000u
#define MC_F405_ADC2_BASE       0x40012100u
#define MC_F405_ADC3_BASE       0x40012200u
#define MC_F405_ADC_COMMON_BASE 0x40012300u
#define MC_F405_SPI2_BASE       0x40003800u /* APB1 */
#define MC_F405_SPI3_BASE       0x40003C00u /* APB1 */
#define MC_F405_SPI1_BASE       0x40013000u /* APB2 */
#define MC_F405_SYSCFG_BASE     0x40013800u /* APB2 */
#define MC_F405_EXTI_BASE       0x40013C00u /* APB2 */
#define MC_F405_GPIOA_BASE      0x40020000u /* AHB1, one port per 0x400 */
#define MC_F405_GPIO_STRIDE     0x400u

/* ---- Timers (TIM1/TIM8: §17.4; TIM2..TIM5: §18.4) ---------------------- */

/** Advanced (TIM1, TIM8) and general-purpose (TIM2..TIM5) timer registers.
 *  RCR and BDTR exist on TIM1/TIM8 only (reserved elsewhere); OR on
 *  TIM2/TIM5 only. TIM2 and TIM5 have 32-bit CNT/ARR/CCRx. */
typedef struct mc_f405_tim_regs {
    volatile uint32_t CR1;   /* 0x00 */
    volatile uint32_t CR2;   /* 0x04 */
    volatile uint32_t SMCR;  /* 0x08 */
    volatile uint32_t DIER;  /* 0x0C */
    volatile uint32_t SR;    /* 0x10 flags, rc_w0 */
    volatile uint32_t EGR;   /* 0x14 write-only event generation */
    volatile uint32_t CCMR1; /* 0x18 */
    volatile uint32_t CCMR2; /* 0x1C */
    volatile uint32_t CCER;  /* 0x20 */
    volatile uint32_t CNT;   /* 0x24 */
    volatile uint32_t PSC;   /* 0x28 */
    volatile uint32_t ARR;   /* 0x2C */
    volatile uint32_t RCR;   /* 0x30 */
    volatile uint32_t CCR1;  /* 0x34 */
    volatile uint32_t CCR2;  /* 0x38 */
    volatile uint32_t CCR3;  /* 0x3C */
    volatile uint32_t CCR4;  /* 0x40 */
    volatile uint32_t BDTR;  /* 0x44 */
    volatile uint32_t DCR;   /* 0x48 */
    volatile uint32_t DMAR;  /* 0x4C */
    volatile uint32_t OR;    /* 0x50 */
} mc_f405_tim_regs_t;

/* CR1 */
#define MC_F405_TIM_CR1_CEN       (1u << 0)
#define MC_F405_TIM_CR1_DIR       (1u << 4)
#define MC_F405_TIM_CR1_CMS_SHIFT 5u /* CMS[6:5] centre-aligned mode */
#define MC_F405_TIM_CR1_CMS_MASK  (3u << 5)
#define MC_F405_TIM_CR1_ARPE      (1u << 7)
/* CR2 */
#define MC_F405_TIM_CR2_MMS_SHIFT 4u /* MMS[6:4] master mode (TRGO) */
#define MC_F405_TIM_CR2_MMS_MASK  (7u << 4)
#define MC_F405_TIM_MMS_UPDATE    2u
#define MC_F405_TIM_MMS_OC4REF    7u
/* SMCR */
#define MC_F405_TIM_SMCR_SMS_MASK 7u /* SMS[2:0] slave mode */
#define MC_F405_TIM_SMS_ENCODER3  3u /* x4: count on TI1 and TI2 edges */
/* SR (all flags rc_w0) and EGR */
#define MC_F405_TIM_SR_UIF (1u << 0)
#define MC_F405_TIM_SR_BIF (1u << 7) /* break interrupt flag */
#define MC_F405_TIM_EGR_UG (1u << 0) /* update generation */
#define MC_F405_TIM_EGR_BG (1u << 7) /* break generation */
/* CCMR1/2, output compare: OCxM[2:0] and OCxPE per channel, channel 1/3 in
 * bits [7:0], channel 2/4 in bits [15:8]. */
#define MC_F405_TIM_OC_PE      (1u << 3) /* preload enable */
#define MC_F405_TIM_OC_M_SHIFT 4u
#define MC_F405_TIM_OCM_PWM1   6u /* active while CNT < CCR */
#define MC_F405_TIM_OCM_PWM2   7u /* active while CNT >= CCR */
/* CCMR1 input capture: CCxS[1:0] = 01 maps ICx on TIx; ICxF[3:0] filter. */
#define MC_F405_TIM_CC1S_TI1   (1u << 0)
#define MC_F405_TIM_CC2S_TI2   (1u << 8)
#define MC_F405_TIM_IC1F_SHIFT 4u
#define MC_F405_TIM_IC2F_SHIFT 12u
/* CCER: 4 bits per channel n (0-based): CCxE, CCxP, CCxNE, CCxNP. */
#define MC_F405_TIM_CCER_E(n)  (1u << (4u * (n)))
#define MC_F405_TIM_CCER_P(n)  (1u << (4u * (n) + 1u))
#define MC_F405_TIM_CCER_NE(n) (1u << (4u * (n) + 2u))
#define MC_F405_TIM_CCER_NP(n) (1u << (4u * (n) + 3u))
/* BDTR (§17.4.18) */
#define MC_F405_TIM_BDTR_DTG_MASK 0xFFu      /* DTG[7:0] dead-time generator */
#define MC_F405_TIM_BDTR_OSSI     (1u << 10) /* idle: outputs forced inactive */
#define MC_F405_TIM_BDTR_OSSR     (1u << 11)
#define MC_F405_TIM_BDTR_BKE      (1u << 12) /* break enable */
#define MC_F405_TIM_BDTR_BKP      (1u << 13) /* break polarity: 1 = active high */
#define MC_F405_TIM_BDTR_AOE      (1u << 14)
#define MC_F405_TIM_BDTR_MOE      (1u << 15) /* main output enable */

/* ---- ADC (§13.13) ------------------------------------------------------ */

typedef struct mc_f405_adc_regs {
    volatile uint32_t SR;      /* 0x00 flags, rc_w0 */
    volatile uint32_t CR1;     /* 0x04 */
    volatile uint32_t CR2;     /* 0x08 */
    volatile uint32_t SMPR1;   /* 0x0C channels 10..18 */
    volatile uint32_t SMPR2;   /* 0x10 channels 0..9 */
    volatile uint32_t JOFR[4]; /* 0x14..0x20 */
    volatile uint32_t HTR;     /* 0x24 */
    volatile uint32_t LTR;     /* 0x28 */
    volatile uint32_t SQR1;    /* 0x2C */
    volatile uint32_t SQR2;    /* 0x30 */
    volatile uint32_t SQR3;    /* 0x34 */
    volatile uint32_t JSQR;    /* 0x38 */
    volatile uint32_t JDR[4];  /* 0x3C..0x48 injected data, rank 1..4 */
    volatile uint32_t DR;      /* 0x4C */
} mc_f405_adc_regs_t;

/** ADC common registers (ADC1 base + 0x300, §13.13.15..17). */
typedef struct mc_f405_adc_common_regs {
    volatile uint32_t CSR; /* 0x00 */
    volatile uint32_t CCR; /* 0x04 */
    volatile uint32_t CDR; /* 0x08 */
} mc_f405_adc_common_regs_t;

/* SR */
#define MC_F405_ADC_SR_EOC  (1u << 1)
#define MC_F405_ADC_SR_JEOC (1u << 2)
#define MC_F405_ADC_SR_OVR  (1u << 5)
/* CR1 */
#define MC_F405_ADC_CR1_JEOCIE (1u << 7)
#define MC_F405_ADC_CR1_SCAN   (1u << 8)
/* CR2 */
#define MC_F405_ADC_CR2_ADON          (1u << 0)
#define MC_F405_ADC_CR2_JEXTSEL_SHIFT 16u /* JEXTSEL[19:16] */
#define MC_F405_ADC_CR2_JEXTEN_SHIFT  20u /* JEXTEN[21:20] */
#define MC_F405_ADC_CR2_SWSTART       (1u << 30)
#define MC_F405_ADC_JEXTSEL_TIM1_CC4  0u  /* §13.6, external trigger for */
#define MC_F405_ADC_JEXTSEL_TIM1_TRGO 1u  /* injected channels table     */
#define MC_F405_ADC_JEXTSEL_TIM8_CC4  14u /* 1110 (TIM8 has no injected TRGO) */
#define MC_F405_ADC_JEXTEN_RISING     1u
/* JSQR: JSQ1..JSQ4 5 bits each from bit 0, JL[21:20] = length - 1. With
 * fewer than 4 conversions the sequence occupies the LAST JSQx fields
 * (JL = 2: JSQ2, JSQ3, JSQ4); results land in JDR1.. in conversion order. */
#define MC_F405_ADC_JSQR_JL_SHIFT    20u
#define MC_F405_ADC_CCR_ADCPRE_SHIFT 16u /* ADCPRE[17:16]: PCLK2 / 2,4,6,8 */
#define MC_F405_ADC_CCR_ADCPRE_MASK  (3u << 16)
#define MC_F405_ADC_DATA_MASK        0xFFFu /* 12-bit right-aligned */

/* ---- bxCAN (§32.9) ----------------------------------------------------- */

typedef struct mc_f405_can_tx_mailbox {
    volatile uint32_t TIR;  /* identifier, TXRQ */
    volatile uint32_t TDTR; /* DLC */
    volatile uint32_t TDLR; /* data bytes 0..3 */
    volatile uint32_t TDHR; /* data bytes 4..7 */
} mc_f405_can_tx_mailbox_t;

typedef struct mc_f405_can_rx_fifo {
    volatile uint32_t RIR;
    volatile uint32_t RDTR;
    volatile uint32_t RDLR;
    volatile uint32_t RDHR;
} mc_f405_can_rx_fifo_t;

typedef struct mc_f405_can_filter_bank {
    volatile uint32_t FR1;
    volatile uint32_t FR2;
} mc_f405_can_filter_bank_t;

#define MC_F405_CAN_FILTER_BANKS 28u

typedef struct mc_f405_can_regs {
    volatile uint32_t MCR;                                  /* 0x000 */
    volatile uint32_t MSR;                                  /* 0x004 */
    volatile uint32_t TSR;                                  /* 0x008 */
    volatile uint32_t RF0R;                                 /* 0x00C */
    volatile uint32_t RF1R;                                 /* 0x010 */
    volatile uint32_t IER;                                  /* 0x014 */
    volatile uint32_t ESR;                                  /* 0x018 */
    volatile uint32_t BTR;                                  /* 0x01C */
    uint32_t reserved0[88];                                 /* 0x020..0x17F */
    mc_f405_can_tx_mailbox_t TX[3];                         /* 0x180..0x1AF */
    mc_f405_can_rx_fifo_t RX[2];                            /* 0x1B0..0x1CF */
    uint32_t reserved1[12];                                 /* 0x1D0..0x1FF */
    volatile uint32_t FMR;                                  /* 0x200 */
    volatile uint32_t FM1R;                                 /* 0x204 */
    uint32_t reserved2;                                     /* 0x208 */
    volatile uint32_t FS1R;                                 /* 0x20C */
    uint32_t reserved3;                                     /* 0x210 */
    volatile uint32_t FFA1R;                                /* 0x214 */
    uint32_t reserved4;                                     /* 0x218 */
    volatile uint32_t FA1R;                                 /* 0x21C */
    uint32_t reserved5[8];                                  /* 0x220..0x23F */
    mc_f405_can_filter_bank_t FB[MC_F405_CAN_FILTER_BANKS]; /* 0x240..0x31F */
} mc_f405_can_regs_t;

/* MCR */
#define MC_F405_CAN_MCR_INRQ  (1u << 0)
#define MC_F405_CAN_MCR_SLEEP (1u << 1)
#define MC_F405_CAN_MCR_TXFP  (1u << 2) /* tx order = request order */
#define MC_F405_CAN_MCR_NART  (1u << 4) /* no automatic retransmission */
#define MC_F405_CAN_MCR_ABOM  (1u << 6) /* automatic bus-off management */
/* MSR */
#define MC_F405_CAN_MSR_INAK (1u << 0)
#define MC_F405_CAN_MSR_SLAK (1u << 1)
/* TSR: TMEx transmit mailbox x empty */
#define MC_F405_CAN_TSR_TME(n) (1u << (26u + (n)))
/* RF0R */
#define MC_F405_CAN_RFR_FMP_MASK 3u        /* FMP[1:0] frames pending */
#define MC_F405_CAN_RFR_FULL     (1u << 3) /* rc_w1 */
#define MC_F405_CAN_RFR_FOVR     (1u << 4) /* overrun, rc_w1 */
#define MC_F405_CAN_RFR_RFOM     (1u << 5) /* release output mailbox */
/* IER */
#define MC_F405_CAN_IER_FMPIE0 (1u << 1)
/* ESR */
#define MC_F405_CAN_ESR_EWGF      (1u << 0) /* error warning (a counter >= 96) */
#define MC_F405_CAN_ESR_EPVF      (1u << 1) /* error passive (a counter > 127) */
#define MC_F405_CAN_ESR_BOFF      (1u << 2) /* bus-off */
#define MC_F405_CAN_ESR_TEC_SHIFT 16u
#define MC_F405_CAN_ESR_REC_SHIFT 24u
/* BTR (§32.7.7 bit timing, §32.9.2 register) */
#define MC_F405_CAN_BTR_TS1_SHIFT 16u /* TS1[19:16] = BS1 - 1 */
#define MC_F405_CAN_BTR_TS2_SHIFT 20u /* TS2[22:20] = BS2 - 1 */
#define MC_F405_CAN_BTR_SJW_SHIFT 24u /* SJW[25:24] = SJW - 1 */
/* TIR / RIR identifier layout (also the filter register layout, §32.7.4) */
#define MC_F405_CAN_IR_TXRQ       (1u << 0)
#define MC_F405_CAN_IR_RTR        (1u << 1)
#define MC_F405_CAN_IR_IDE        (1u << 2)
#define MC_F405_CAN_IR_STID_SHIFT 21u /* STID[10:0] at [31:21] */
#define MC_F405_CAN_IR_EXID_SHIFT 3u  /* 29-bit id at [31:3] */
#define MC_F405_CAN_DTR_DLC_MASK  0xFu
/* FMR */
#define MC_F405_CAN_FMR_FINIT (1u << 0)

/* ---- SPI (§28.5; the I2S registers are not used) ----------------------- */

typedef struct mc_f405_spi_regs {
    volatile uint32_t CR1;     /* 0x00 */
    volatile uint32_t CR2;     /* 0x04 */
    volatile uint32_t SR;      /* 0x08 flags (RXNE, TXE, BSY read-only) */
    volatile uint32_t DR;      /* 0x0C data: write = transmit, read = receive */
    volatile uint32_t CRCPR;   /* 0x10 */
    volatile uint32_t RXCRCR;  /* 0x14 */
    volatile uint32_t TXCRCR;  /* 0x18 */
    volatile uint32_t I2SCFGR; /* 0x1C */
    volatile uint32_t I2SPR;   /* 0x20 */
} mc_f405_spi_regs_t;

/* CR1 (§28.5.1) */
#define MC_F405_SPI_CR1_CPHA     (1u << 0) /* 1: data captured on the second edge */
#define MC_F405_SPI_CR1_CPOL     (1u << 1) /* 1: SCK idles high */
#define MC_F405_SPI_CR1_MSTR     (1u << 2)
#define MC_F405_SPI_CR1_BR_SHIFT 3u /* BR[5:3]: fPCLK / 2^(BR + 1) */
#define MC_F405_SPI_CR1_BR_MASK  (7u << 3)
#define MC_F405_SPI_CR1_SPE      (1u << 6) /* SPI enable */
#define MC_F405_SPI_CR1_LSBFIRST (1u << 7)
#define MC_F405_SPI_CR1_SSI      (1u << 8)  /* internal NSS level (with SSM) */
#define MC_F405_SPI_CR1_SSM      (1u << 9)  /* software slave management */
#define MC_F405_SPI_CR1_DFF      (1u << 11) /* 1: 16-bit frames */
/* SR (§28.5.3) */
#define MC_F405_SPI_SR_RXNE (1u << 0)
#define MC_F405_SPI_SR_TXE  (1u << 1)
#define MC_F405_SPI_SR_MODF (1u << 5)
#define MC_F405_SPI_SR_OVR  (1u << 6)
#define MC_F405_SPI_SR_BSY  (1u << 7)

/* ---- GPIO (§8.4) ------------------------------------------------------- */

typedef struct mc_f405_gpio_regs {
    volatile uint32_t MODER;   /* 0x00 2 bits per pin: 00 in, 01 out */
    volatile uint32_t OTYPER;  /* 0x04 */
    volatile uint32_t OSPEEDR; /* 0x08 */
    volatile uint32_t PUPDR;   /* 0x0C */
    volatile uint32_t IDR;     /* 0x10 */
    volatile uint32_t ODR;     /* 0x14 */
    volatile uint32_t BSRR;    /* 0x18 write-only: set [15:0], reset [31:16] */
    volatile uint32_t LCKR;    /* 0x1C */
    volatile uint32_t AFR[2];  /* 0x20, 0x24 */
} mc_f405_gpio_regs_t;

#define MC_F405_GPIO_MODER_OUTPUT 1u
/** Ports A..I of the STM32F405/407 (LQFP64 bonds A, B, C, D2 and H0/H1). */
#define MC_F405_GPIO_PORTS 9u

/* ---- SYSCFG (§9.2) and EXTI (§12.3) ----------------------------------- */

typedef struct mc_f405_syscfg_regs {
    volatile uint32_t MEMRMP;    /* 0x00 */
    volatile uint32_t PMC;       /* 0x04 */
    volatile uint32_t EXTICR[4]; /* 0x08..0x14: EXTIx[3:0] = port of line x
                                    (0 = A .. 8 = I), 4 lines per register */
    volatile uint32_t RESERVED[2];
    volatile uint32_t CMPCR; /* 0x20 */
} mc_f405_syscfg_regs_t;

/** EXTI lines 0..22, one bit each (0..15: GPIO pin number of any port). */
typedef struct mc_f405_exti_regs {
    volatile uint32_t IMR;   /* 0x00 interrupt mask: 1 = line's interrupt enabled */
    volatile uint32_t EMR;   /* 0x04 event mask */
    volatile uint32_t RTSR;  /* 0x08 rising-edge trigger */
    volatile uint32_t FTSR;  /* 0x0C falling-edge trigger */
    volatile uint32_t SWIER; /* 0x10 software interrupt */
    volatile uint32_t PR;    /* 0x14 pending, rc_w1 (write 1 clears) */
} mc_f405_exti_regs_t;

/** RCC_APB2ENR SYSCFGEN (§7.3.14): SYSCFG clock (EXTICR writes need it). */
#define MC_F405_RCC_APB2ENR_SYSCFGEN (1u << 14)

/* ---- Peripheral pointers on the MCU ------------------------------------ */

#define MC_F405_TIM1       ((mc_f405_tim_regs_t *)(uintptr_t)MC_F405_TIM1_BASE)
#define MC_F405_TIM2       ((mc_f405_tim_regs_t *)(uintptr_t)MC_F405_TIM2_BASE)
#define MC_F405_TIM3       ((mc_f405_tim_regs_t *)(uintptr_t)MC_F405_TIM3_BASE)
#define MC_F405_TIM4       ((mc_f405_tim_regs_t *)(uintptr_t)MC_F405_TIM4_BASE)
#define MC_F405_TIM5       ((mc_f405_tim_regs_t *)(uintptr_t)MC_F405_TIM5_BASE)
#define MC_F405_TIM8       ((mc_f405_tim_regs_t *)(uintptr_t)MC_F405_TIM8_BASE)
#define MC_F405_ADC1       ((mc_f405_adc_regs_t *)(uintptr_t)MC_F405_ADC1_BASE)
#define MC_F405_ADC_COMMON ((mc_f405_adc_common_regs_t *)(uintptr_t)MC_F405_ADC_COMMON_BASE)
#define MC_F405_CAN1       ((mc_f405_can_regs_t *)(uintptr_t)MC_F405_CAN1_BASE)
#define MC_F405_SPI3       ((mc_f405_spi_regs_t *)(uintptr_t)MC_F405_SPI3_BASE)
#define MC_F405_SYSCFG     ((mc_f405_syscfg_regs_t *)(uintptr_t)MC_F405_SYSCFG_BASE)
#define MC_F405_EXTI       ((mc_f405_exti_regs_t *)(uintptr_t)MC_F405_EXTI_BASE)
/** GPIO port n: 0 = A, 1 = B, ... */
#define MC_F405_GPIO(n) ((mc_f405_gpio_regs_t *)(MC_F405_GPIOA_BASE + MC_F405_GPIO_STRIDE * (n)))

/* ---- Layout checks against the RM0090 register maps -------------------- */

#ifndef __cplusplus
_Static_assert(offsetof(mc_f405_tim_regs_t, CCER) == 0x20u, "TIM CCER");
_Static_assert(offsetof(mc_f405_tim_regs_t, ARR) == 0x2Cu, "TIM ARR");
_Static_assert(offsetof(mc_f405_tim_regs_t, CCR4) == 0x40u, "TIM CCR4");
_Static_assert(offsetof(mc_f405_tim_regs_t, BDTR) == 0x44u, "TIM BDTR");
_Static_assert(offsetof(mc_f405_tim_regs_t, OR) == 0x50u, "TIM OR");
_Static_assert(offsetof(mc_f405_adc_regs_t, JSQR) == 0x38u, "ADC JSQR");
_Static_assert(offsetof(mc_f405_adc_regs_t, JDR) == 0x3Cu, "ADC JDR1");
_Static_assert(offsetof(mc_f405_adc_regs_t, DR) == 0x4Cu, "ADC DR");
_Static_assert(offsetof(mc_f405_can_regs_t, BTR) == 0x1Cu, "CAN BTR");
_Static_assert(offsetof(mc_f405_can_regs_t, TX) == 0x180u, "CAN TI0R");
_Static_assert(offsetof(mc_f405_can_regs_t, RX) == 0x1B0u, "CAN RI0R");
_Static_assert(offsetof(mc_f405_can_regs_t, FMR) == 0x200u, "CAN FMR");
_Static_assert(offsetof(mc_f405_can_regs_t, FA1R) == 0x21Cu, "CAN FA1R");
_Static_assert(offsetof(mc_f405_can_regs_t, FB) == 0x240u, "CAN F0R1");
_Static_assert(sizeof(mc_f405_can_regs_t) == 0x320u, "CAN size");
_Static_assert(offsetof(mc_f405_gpio_regs_t, BSRR) == 0x18u, "GPIO BSRR");
_Static_assert(offsetof(mc_f405_gpio_regs_t, AFR) == 0x20u, "GPIO AFRL");
_Static_assert(offsetof(mc_f405_spi_regs_t, DR) == 0x0Cu, "SPI DR");
_Static_assert(offsetof(mc_f405_spi_regs_t, I2SPR) == 0x20u, "SPI I2SPR");
_Static_assert(offsetof(mc_f405_syscfg_regs_t, EXTICR) == 0x08u, "SYSCFG EXTICR1");
_Static_assert(offsetof(mc_f405_syscfg_regs_t, CMPCR) == 0x20u, "SYSCFG CMPCR");
_Static_assert(offsetof(mc_f405_exti_regs_t, PR) == 0x14u, "EXTI PR");
#endif

#ifdef __cplusplus
}
#endif

#endif /* MC_F405_REGS_H */
