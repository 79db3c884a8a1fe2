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
  # Generated at every build (git_hash.cmake), not at configure time.
  get_filename_component(root ${MDTOOL_DIR}/../.. ABSOLUTE)
  set(gen ${CMAKE_CURRENT_BINARY_DIR}/mdtool_gen)
  add_custom_target(mdtool_git_hash
    COMMAND ${CMAKE_COMMAND} -DROOT=${root} -DOUT=${gen}/mdtool_git_hash.h
            -P ${MDTOOL_DIR}/git_hash.cmake
    BYPRODUCTS ${gen}/mdtool_git_hash.h
    COMMENT "mdtool: git hash of the tree")
  nanobind_add_module(_sil NB_STATIC ${MDTOOL_DIR}/csrc/sil_module.cpp)
  # Scenarios register themselves from static initialisers: keep every object.
  target_link_libraries(_sil PRIVATE $<LINK_LIBRARY:WHOLE_ARCHIVE,mcsim_scenarios>)
  add_dependencies(_sil mdtool_git_hash)
  target_include_directories(_sil PRIVATE ${gen})
  # Debug or Release: the benchmark says which it measured.
  target_compile_definitions(_sil PRIVATE MDTOOL_BUILD_TYPE="$<IF:$<CONFIG:>,none,$<CONFIG>>")
  set_target_properties(_sil PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${out_dir})
endfunction()
