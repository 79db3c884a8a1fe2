# Applied after GoogleTest discovery (see tests/CMakeLists.txt): a timeout
# for each PIL test, which starts and drives its own QEMU. Generous: a
# lock-step run only slows down on a loaded machine, and nothing in its
# criteria depends on the wall clock.
foreach(t IN LISTS test_pil_foc_TESTS)
  set_tests_properties("${t}" PROPERTIES TIMEOUT 120)
endforeach()
foreach(t IN LISTS test_pil_app_target_TESTS)
  set_tests_properties("${t}" PROPERTIES TIMEOUT 600)
endforeach()
