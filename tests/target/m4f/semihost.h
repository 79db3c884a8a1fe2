/* ARM semihosting for target tests: text out and exit code back to QEMU
 * (-semihosting-config enable=on,target=native), so CTest can judge. */
#ifndef MC_SEMIHOST_H
#define MC_SEMIHOST_H
void mc_sh_write0(const char *s);
void mc_sh_exit(int code) __attribute__((noreturn));
#endif
