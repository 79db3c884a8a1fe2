/* Target side of the bit-exactness sweep: semihosting to QEMU's stdout. */
#include "bitexact.h"
#include "m4f/semihost.h"
void mc_bx_emit(const char *s)
{
    mc_sh_write0(s);
}
int main(void)
{
    return mc_bitexact_run();
}
