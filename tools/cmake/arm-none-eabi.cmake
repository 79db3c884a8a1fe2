# Toolchain file: STM32F405 (Cortex-M4F, single-precision FPU, hard float ABI).
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

find_program(MC_ARM_GCC arm-none-eabi-gcc REQUIRED)
set(CMAKE_C_COMPILER   arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_ASM_COMPILER arm-none-eabi-gcc)
set(CMAKE_AR           arm-none-eabi-ar)
set(CMAKE_RANLIB       arm-none-eabi-ranlib)
set(CMAKE_SIZE         arm-none-eabi-size)
set(CMAKE_OBJCOPY      arm-none-eabi-objcopy)

# No OS: test compilations must not try to link a hosted executable.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

# The flags themselves are in mc_m4f_flags.cmake (shared with tests/target).
include(${CMAKE_CURRENT_LIST_DIR}/mc_m4f_flags.cmake)
string(JOIN " " MC_CPU_FLAGS ${MC_M4F_CPU_FLAGS})
string(JOIN " " MC_SECTION_FLAGS ${MC_M4F_SECTION_FLAGS})
string(JOIN " " MC_LINK_FLAGS ${MC_M4F_LINK_FLAGS})
set(CMAKE_C_FLAGS_INIT   "${MC_CPU_FLAGS} ${MC_SECTION_FLAGS}")
set(CMAKE_CXX_FLAGS_INIT "${MC_CPU_FLAGS} ${MC_SECTION_FLAGS}")
set(CMAKE_ASM_FLAGS_INIT "${MC_CPU_FLAGS}")
set(CMAKE_EXE_LINKER_FLAGS_INIT "${MC_CPU_FLAGS} ${MC_LINK_FLAGS}")

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
