/* q31 bit-exactness sweep: every q31 twin kernel (and its init, which forms
 * the gains in float) over deterministic inputs, one line per kernel,
 * "<name> <count> <fnv1a-hash>", on the host and on the emulated Cortex-M3
 * (no FPU: soft float for init only) and Cortex-M4F. */
#ifndef MC_Q31_SWEEP_H
#define MC_Q31_SWEEP_H
void mc_q31_emit(const char *s);
int mc_q31_sweep_run(void);
#endif
