/* An out-of-range mode can only be made in C: in C++ a value outside the
 * enum's value range (0..3 here) is undefined behaviour. */
#include "mc_drive.h"

int mc_test_set_mode_raw(mc_drive_t *d, int mode);

int mc_test_set_mode_raw(mc_drive_t *d, int mode)
{
    return mc_drive_set_mode(d, (mc_drive_mode_t)mode);
}
