/* Configurations of the q31 kernels shared by the bit-exactness sweep and
 * the instruction-count cases (tests/target/q31, tools/bench/bench_cases_q31.c):
 * the operating points of the unit tests and SIL loops (paper-002 test
 * motor, paper 000 Section V, paper 001 Fig. 2). */
#ifndef MC_Q31_KERNELS_CFG_H
#define MC_Q31_KERNELS_CFG_H

#include "csmc/mc_csmc_q31.h"
#include "observer/mc_hgo_q31.h"
#include "filters/mc_ddiff_q31.h"
#include "foc/mc_foc_q31.h"
#include "observer/mc_fluxobs_q31.h"
#include "observer/mc_spdpll_q31.h"
#include "pi2d/mc_pi2d_q31.h"

void mc_q31cfg_ddiff(mc_ddiff_q31_cfg_t *c);
void mc_q31cfg_spdpll(mc_spdpll_q31_cfg_t *c);
void mc_q31cfg_fluxobs(mc_fluxobs_q31_cfg_t *c);
void mc_q31cfg_foc(mc_foc_q31_cfg_t *c);
void mc_q31cfg_pi2d(mc_pi2d_q31_cfg_t *c);
void mc_q31cfg_csmc(mc_csmc_q31_cfg_t *c);
void mc_q31cfg_hgo(mc_hgo_q31_cfg_t *c);

#endif /* MC_Q31_KERNELS_CFG_H */
