/**
 * @file mc_board_gpio.c
 * @brief Applies a board's generated GPIO table (mc_board_desc.h).
 *        Register facts: RM0090 §8.4 (GPIO registers).
 */
#include "mc_board_desc.h"

#include <stddef.h>

static uint32_t merge(uint32_t reg, uint32_t mask, uint32_t value)
{
    return (reg & ~mask) | (value & mask);
}

void mc_board_gpio_apply(const mc_board_gpio_port_init_t *p_table, uint32_t n,
                         mc_f405_gpio_regs_t *const p_ports[MC_F405_GPIO_PORTS])
{
    uint32_t k;

    if ((p_table == NULL) || (p_ports == NULL)) {
        return;
    }
    for (k = 0u; k < n; k++) {
        const mc_board_gpio_port_init_t *e = &p_table[k];
        mc_f405_gpio_regs_t *g;

        if (e->port >= MC_F405_GPIO_PORTS) {
            continue;
        }
        g = p_ports[e->port];
        if (g == NULL) {
            continue;
        }
        if (e->bsrr != 0u) {
            g->BSRR = e->bsrr; /* ODR levels before any pin becomes an output */
        }
        g->OTYPER = merge(g->OTYPER, e->otyper_mask, e->otyper);
        g->OSPEEDR = merge(g->OSPEEDR, e->ospeedr_mask, e->ospeedr);
        g->PUPDR = merge(g->PUPDR, e->pupdr_mask, e->pupdr);
        g->AFR[0] = merge(g->AFR[0], e->afrl_mask, e->afrl);
        g->AFR[1] = merge(g->AFR[1], e->afrh_mask, e->afrh);
        g->MODER = merge(g->MODER, e->moder_mask, e->moder);
    }
}
