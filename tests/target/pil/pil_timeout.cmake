# Applied after GoogleTest discovery (see tests/CMakeLists.txt): a timeout
# for each PIL test, which starts and drives its own QEMU.
foreach(t IN LISTS test_pil_foc_TESTS)
  set_tests_properties("${t}" PROPERTIES TIMEOUT 60)
endforeach()
