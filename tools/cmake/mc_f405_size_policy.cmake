# The drive images' optimisation policy, stated once: read by the images
# (firmware/targets/stm32f405/CMakeLists.txt) and by their mirrors in
# tests/target (the interrupt benchmark bench_isr, the PIL image), so the
# instruction counts and the PIL run measure the code the board runs.
#
# The images' code builds at -O2 with link-time optimisation (the reasons
# next to mc_f405_interrupt_code_o2); MC_F405_OS_SOURCES, code neither the
# fast nor the CAN-receive interrupt's measured path runs
# (tools/bench/bench_isr.c counts the fast, CAN-receive and slow
# interrupts, the slow one under a flood of parameter reads), builds at -Os
# against the images' 128 KiB flash budget (issue 19):
# - the configuration: deriving and checking a configuration's gains, the
#   store, the parameter tables' data;
# - commissioning: its plug-in runs in the fast interrupt only while a
#   motor is being measured (the FOC kernels it calls stay at -O2), the
#   identification kernels only for it, its CAN front end in the slow loop,
#   its checks once at the end of the flux step's coast, the Hall table's
#   derivation once after its sweep, the anticogging calibration's step in
#   the slow loop while it calibrates; the board's commissioning limits
#   once from the configuration; likewise the encoder's angle finders
#   (mc_ctrl_align.c: the alignment and the index search run in the fast
#   interrupt only while an enable finds the offset, in place of the speed
#   law, before the measured paths run);
# - start-up: the reset handler, the clock tree, the pins' set-up, the
#   jump to the bootloader (all before or instead of the interrupts);
# - the slow loop's own work (PendSV, 1 kHz): the CAN command handler, the
#   parameter server and lookup, telemetry and its frames' packing, the
#   bootloader request, the thermal model. The slow loop's counts rise
#   (the bench's slow and flood rows): even the flood (16 commands answered
#   in one step) stays a small part of the 1 ms period (the CPU budget
#   table of firmware/targets/stm32f405/README.md). The application itself
#   (mc_app.c) stays at -O2: at -Os (1.2 KB less) the PIL's can-telemetry
#   run overflows the 4 KiB main stack's guard band.
# Float results do not depend on the level (FMA contraction is off; the
# PIL tests compare the image with the SIL bit for bit).
# The interrupts' level: -O2, its basic blocks laid out in source order
# (-freorder-blocks-algorithm=simple: -O2's default duplicates blocks to
# save taken branches) and no scheduling before register allocation
# (-fno-schedule-insns: the M4's in-order pipeline gains little from it and
# the extra live registers cost spills): less code, and no more
# instructions on the measured interrupt paths (target.bench_isr).
set(MC_F405_O2_FLAGS -O2 -freorder-blocks-algorithm=simple -fno-schedule-insns)
get_filename_component(_mc_root ${CMAKE_CURRENT_LIST_DIR}/../.. ABSOLUTE)
set(_mc_app ${_mc_root}/firmware/app)
set(_mc_f405 ${_mc_root}/firmware/targets/stm32f405)
set(MC_F405_OS_SOURCES
  # configuration
  ${_mc_app}/config/mc_gains.c ${_mc_app}/config/mc_law_cfg.c ${_mc_app}/config/mc_cfg_store.c
  ${_mc_app}/config/mc_params_gen.c
  # commissioning, the angle finders
  ${_mc_app}/commission/mc_commission.c ${_mc_app}/commission/mc_comm_can.c
  ${_mc_app}/commission/mc_comm_check.c ${_mc_app}/commission/mc_comm_hall.c
  ${_mc_app}/commission/mc_comm_cog.c ${_mc_root}/firmware/kernels/ident/mc_ident.c
  ${_mc_f405}/mc_board_comm.c ${_mc_app}/ctrl/mc_ctrl_align.c
  # start-up
  ${_mc_f405}/startup_stm32f405.c ${_mc_f405}/mc_clock.c ${_mc_f405}/boards/mc_board_gpio.c
  ${_mc_f405}/mc_boot_handoff.c
  # the slow loop's own work
  ${_mc_app}/can/mc_can_cmd.c ${_mc_app}/can/mc_telemetry.c ${_mc_app}/can/mc_can_proto.c
  ${_mc_app}/can/mc_boot_enter.c ${_mc_app}/can/mc_boot_proto.c ${_mc_app}/config/mc_param_srv.c
  ${_mc_app}/config/mc_params.c ${_mc_app}/drive/mc_drive_thermal.c)
