/* Target side of the q31 sweep: semihosting. */
#include "m4f/semihost.h"
#include "q31_sweep.h"

void mc_q31_emit(const char *s)
{
    mc_sh_write0(s);
}

int main(void)
{
    return mc_q31_sweep_run();
}
