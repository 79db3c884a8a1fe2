# cmake -DROOT=<repository> -DOUT=<header> -P git_hash.cmake
# Writes OUT = '#define MDTOOL_GIT_HASH "<git describe --always --dirty>"'
# ("unknown" outside a git checkout), and only when that text changes, so
# the extension is rebuilt when the commit changes and not otherwise. Run on
# every build (sil_module.cmake): the hash is that of the tree built, not of
# the tree configured.
execute_process(COMMAND git -C ${ROOT} describe --always --dirty --abbrev=40
                OUTPUT_VARIABLE hash OUTPUT_STRIP_TRAILING_WHITESPACE
                RESULT_VARIABLE rc ERROR_QUIET)
if(NOT rc EQUAL 0 OR hash STREQUAL "")
  set(hash "unknown")
endif()
set(text "#define MDTOOL_GIT_HASH \"${hash}\"\n")
set(old "")
if(EXISTS ${OUT})
  file(READ ${OUT} old)
endif()
if(NOT old STREQUAL text)
  file(WRITE ${OUT} "${text}")
endif()
