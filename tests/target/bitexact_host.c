/* Host side of the bit-exactness sweep: stdout. */
#include <stdio.h>
#include "bitexact.h"
void mc_bx_emit(const char *s)
{
    fputs(s, stdout);
}
int main(void)
{
    return mc_bitexact_run();
}
