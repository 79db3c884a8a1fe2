/* Host side of the q31 sweep: stdout. */
#include <stdio.h>

#include "q31_sweep.h"

void mc_q31_emit(const char *s)
{
    (void)fputs(s, stdout);
}

int main(void)
{
    return mc_q31_sweep_run();
}
