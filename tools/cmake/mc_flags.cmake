# Compiler flags shared by every build, host and target.
#
# -ffp-contract=off: no fused multiply-add contraction, so the same C source
#   gives bit-identical float results on x86-64 and on the Cortex-M4F.
# -fno-math-errno: lets sqrtf-like builtins map to instructions; kernels do not
#   use libm anyway (own math in firmware/kernels/math).
include(${CMAKE_CURRENT_LIST_DIR}/mc_m4f_flags.cmake)
add_compile_options(${MC_FP_FLAGS})

# Warnings for firmware C code (kernels, app, MCU HAL): all of them are errors.
# -Wdouble-promotion matters on the M4F: a stray double literal turns a
# single-cycle FPU op into a software double routine.
set(MC_FIRMWARE_C_WARNINGS
  -Wall -Wextra -Wconversion -Wsign-conversion -Wshadow -Wdouble-promotion
  -Wstrict-prototypes -Wmissing-prototypes -Wundef -Wcast-align -Wvla
  -Werror)

# Warnings for host C++ (simulator, host HAL, tests). Eigen is included as a
# system header so its own warnings do not count against us.
set(MC_HOST_CXX_WARNINGS -Wall -Wextra -Wshadow -Werror)

if(MC_SANITIZE AND NOT CMAKE_CROSSCOMPILING)
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=all
                      -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()

# mc_firmware_target(<target>): apply the firmware warning set.
function(mc_firmware_target tgt)
  target_compile_options(${tgt} PRIVATE
    $<$<COMPILE_LANGUAGE:C>:${MC_FIRMWARE_C_WARNINGS}>)
endfunction()
