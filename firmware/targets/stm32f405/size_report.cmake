# cmake -DSIZE=<arm-none-eabi-size> -DELF=<image> -DBUDGET=ON|OFF [-DLABEL=<text>]
#       [-DFLASH_MAX=<bytes> -DRAM_MAX=<bytes>] -P size_report.cmake
# Prints `size` (Berkeley) and the use of each memory region, from the
# section addresses: flash 0x08000000 (what is programmed: code, constants,
# .data initialisers), SRAM 0x20000000 (.data, .bss, the reserved stack),
# CCM 0x10000000. With BUDGET=ON, fails above FLASH_MAX bytes of flash or
# RAM_MAX bytes of RAM (SRAM + CCM), the drive image's budget.
execute_process(COMMAND ${SIZE} ${ELF} OUTPUT_VARIABLE berkeley RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "size failed on ${ELF}")
endif()
execute_process(COMMAND ${SIZE} -A -d ${ELF} OUTPUT_VARIABLE sysv)
string(REPLACE "\n" ";" lines "${sysv}")
set(flash 0)
set(sram 0)
set(ccm 0)
set(data 0)
foreach(line IN LISTS lines)
  if(line MATCHES "^([.A-Za-z_][^ ]*) +([0-9]+) +([0-9]+)")
    set(sec ${CMAKE_MATCH_1})
    set(sz ${CMAKE_MATCH_2})
    set(addr ${CMAKE_MATCH_3})
    if(sz EQUAL 0)
      continue()
    endif()
    if(addr GREATER_EQUAL 134217728 AND addr LESS 135266304)       # 0x08000000 + 1 MiB
      math(EXPR flash "${flash} + ${sz}")
    elseif(addr GREATER_EQUAL 536870912 AND addr LESS 537001984)   # 0x20000000 + 128 KiB
      math(EXPR sram "${sram} + ${sz}")
      if(sec STREQUAL ".data")
        math(EXPR flash "${flash} + ${sz}")                        # initialisers in flash
      endif()
    elseif(addr GREATER_EQUAL 268435456 AND addr LESS 268500992)   # 0x10000000 + 64 KiB
      math(EXPR ccm "${ccm} + ${sz}")
    endif()
  endif()
endforeach()
get_filename_component(name ${ELF} NAME)
if(DEFINED LABEL AND NOT LABEL STREQUAL "")
  set(name "${name} (${LABEL})")
endif()
math(EXPR ram "${sram} + ${ccm}")
string(STRIP "${berkeley}" berkeley)
message("${berkeley}")
message("${name}: flash ${flash} B of 1048576, SRAM ${sram} B of 131072 (stack included), CCM ${ccm} B of 65536")
if(BUDGET)
  if(NOT DEFINED FLASH_MAX OR NOT DEFINED RAM_MAX)
    message(FATAL_ERROR "size_report.cmake: BUDGET=ON needs FLASH_MAX and RAM_MAX")
  endif()
  if(flash GREATER FLASH_MAX OR ram GREATER RAM_MAX)
    message(FATAL_ERROR "${name} over budget: flash ${flash} B (max ${FLASH_MAX}), RAM ${ram} B (max ${RAM_MAX})")
  endif()
  message("${name}: within budget (flash ${flash} <= ${FLASH_MAX} B, RAM ${ram} <= ${RAM_MAX} B)")
endif()
