/**
 * @file mc_gains.c
 * @brief Controller gains from the motor's values: see mc_gains.h.
 */
#include "mc_gains.h"

#include <stddef.h>

static int positive_finite(double x)
{
    return (x > 0.0) && (x < 1e300); /* NaN fails both, inf the second */
}

double mc_gains_kt_nm_a(double pole_pairs, double flux_wb)
{
    return 1.5 * pole_pairs * flux_wb;
}

double mc_gains_speed_wc_rad_s(double cur_bw_rad_s, double enc_pll_bw_rad_s)
{
    const double a = cur_bw_rad_s / 10.0;
    const double b = enc_pll_bw_rad_s / 4.0;
    return (b < a) ? b : a;
}

uint32_t mc_gains_speed_pi(double j_kgm2, double kt_nm_a, double wc_rad_s, float *p_kp_a_s_rad,
                           float *p_ki_a_rad)
{
    if ((p_kp_a_s_rad == NULL) || (p_ki_a_rad == NULL) || !positive_finite(j_kgm2) ||
        !positive_finite(kt_nm_a) || !positive_finite(wc_rad_s)) {
        return MC_GAINS_ERR_VALUE;
    }
    {
        const float kp = (float)(j_kgm2 * wc_rad_s / kt_nm_a);
        *p_kp_a_s_rad = kp;
        *p_ki_a_rad = (float)((double)kp * wc_rad_s / 4.0);
    }
    return MC_GAINS_OK;
}
