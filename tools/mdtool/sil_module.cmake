# mdtool_add_sil_module(<out_dir>): the Python extension mdtool._sil (the
# mcsim scenario runner, tools/mdtool/csrc/sil_module.cpp) with nanobind.
# Used by tools/mdtool/CMakeLists.txt (pip install ./tools/mdtool) and by the
# test tree (tests/sil/campaign), which builds it next to mcsim with the same
# flags. Needs nanobind's CMake package (nanobind_DIR) and every host target
# compiled as position-independent code.
set(MDTOOL_DIR ${CMAKE_CURRENT_LIST_DIR})

function(mdtool_add_sil_module out_dir)
  find_package(Python 3.9 REQUIRED COMPONENTS Interpreter Development.Module)
  find_package(nanobind CONFIG REQUIRED)
  # The firmware commit the module is built from: a campaign writes it into
  # every row (tools/mdtool/README.md). "-dirty" when the tree had changes.
  get_filename_component(root ${MDTOOL_DIR}/../.. ABSOLUTE)
  execute_process(COMMAND git -C ${root} describe --always --dirty --abbrev=40
                  OUTPUT_VARIABLE hash OUTPUT_STRIP_TRAILING_WHITESPACE
                  RESULT_VARIABLE rc ERROR_QUIET)
  if(NOT rc EQUAL 0 OR hash STREQUAL "")
    set(hash "unknown")
  endif()
  nanobind_add_module(_sil NB_STATIC ${MDTOOL_DIR}/csrc/sil_module.cpp)
  # Scenarios register themselves from static initialisers: keep every object.
  target_link_libraries(_sil PRIVATE $<LINK_LIBRARY:WHOLE_ARCHIVE,mcsim_scenarios>)
  target_compile_definitions(_sil PRIVATE MDTOOL_GIT_HASH="${hash}")
  set_target_properties(_sil PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${out_dir})
endfunction()
