# Run by ctest after the test programs' discovered tests are added (TEST_INCLUDE_FILES):
# every test listed in tests/slow_tests.txt gets the label `slow` instead of `quick`.
file(STRINGS "${CMAKE_CURRENT_LIST_DIR}/slow_tests.txt" navtwin_slow_tests REGEX "^[^#]")
foreach(navtwin_test IN LISTS navtwin_slow_tests)
  if(TEST "${navtwin_test}")
    set_tests_properties("${navtwin_test}" PROPERTIES LABELS slow)
  endif()
endforeach()
