/* Bit-exactness sweep: runs the kernels over deterministic inputs and prints
 * one line per kernel, "<name> <count> <fnv1a-hash>", identically formatted on
 * the host and on the emulated Cortex-M4F. tests/target compares the two. */
#ifndef MC_BITEXACT_H
#define MC_BITEXACT_H
/* Platform output: host uses stdio, target uses semihosting. */
void mc_bx_emit(const char *s);
int mc_bitexact_run(void);
#endif
