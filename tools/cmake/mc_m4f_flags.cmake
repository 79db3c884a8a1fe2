# The Cortex-M4F's code-generation flags, stated once. Read by the
# toolchain file (arm-none-eabi.cmake: the firmware images of the
# stm32f405 presets) and by mc_flags.cmake (the host build, whose
# tests/target compiles the same sources for the M4F by calling
# arm-none-eabi-gcc directly), so the images and the bit-exactness, PIL
# and instruction-count tests cannot drift apart.
#
#   MC_M4F_CPU_FLAGS      core, instruction set, FPU and float ABI
#   MC_M4F_SECTION_FLAGS  one section per function/object (--gc-sections)
#   MC_M4F_LINK_FLAGS     garbage-collect unused sections at link
#   MC_FP_FLAGS           no FMA contraction: the same float results on
#                         x86-64 and on the M4F (every build, host too)
#   MC_M4F_LTO_FLAGS      link-time optimisation of the drive images (and
#                         of their mirrors in tests/target: the interrupt
#                         benchmark, the PIL image): one partition, so one
#                         optimisation of the whole image, deterministic
include_guard(GLOBAL)
set(MC_M4F_CPU_FLAGS -mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard)
set(MC_M4F_SECTION_FLAGS -ffunction-sections -fdata-sections)
set(MC_M4F_LINK_FLAGS -Wl,--gc-sections)
set(MC_FP_FLAGS -ffp-contract=off)
set(MC_M4F_LTO_FLAGS -flto -flto-partition=one)
