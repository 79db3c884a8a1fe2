/**
 * @file bench_isr_main.c
 * @brief The drive image's main.c, unchanged, for the interrupt benchmark
 *        (bench_isr.h): its `main` renamed (the bench replays the set-up),
 *        accessors to its statics.
 */
#include <string.h>

#include "bench_isr.h"

int mc_image_main(void);
#define main mc_image_main
#include "main.c" /* NOLINT(bugprone-suspicious-include): the image's own code */
#undef main

int bench_image_start(const mc_hal_t *hal, const mc_app_cfg_t *app_cfg)
{
    memset(&g_drive, 0, sizeof g_drive);
    memset(&g_comm, 0, sizeof g_comm);
    memset(&g_comm_can, 0, sizeof g_comm_can);
    g_running = false;
    g_app_on = false;
    /* as main() */
    (void)mc_app_boot(&g_app, app_cfg);
    if (mc_app_start(&g_app, &g_drive, hal, hal->can, true) != MC_APP_CFG_OK) {
        return 1;
    }
    const mc_comm_can_cfg_t *comm_cfg = mc_board_comm_cfg(&g_app.params);
    if ((comm_cfg != NULL) &&
        (mc_comm_can_init(&g_comm_can, comm_cfg, &g_comm, &g_drive,
                          g_app.params_valid ? &g_app.srv : NULL) == MC_COMM_CAN_CFG_OK)) {
        mc_app_attach_commission(&g_app, &g_comm_can);
    }
    g_app_on = true;
    mc_nvic_set_priority(MC_IRQ_ADC, MC_PRIO_FAST_LOOP);
    mc_scb_set_pendsv_priority(MC_PRIO_SLOW_LOOP);
    g_running = true;
    mc_board_start();
    return 0;
}

mc_drive_t *bench_image_drive(void)
{
    return &g_drive;
}

mc_app_t *bench_image_app(void)
{
    return &g_app;
}
