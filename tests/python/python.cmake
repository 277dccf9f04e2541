# pytest tests of the Python module (tests/python/*.py), labelled gl: they make OSMesa contexts.
# The module cannot be loaded into a Python without ASan, so the sanitizer build skips them.
foreach(name bindings sweep docs_example)
  if(AG_SANITIZE)
    add_test(NAME python.${name} COMMAND sh -c "echo 'python tests: skipped under ASan'; exit 77")
  else()
    add_test(NAME python.${name}
             COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/python/run_pytest.sh ${AG_PYTHON}
                     $<TARGET_FILE:afterglow> ${PROJECT_BINARY_DIR}/python
                     ${CMAKE_CURRENT_SOURCE_DIR}/python/test_${name}.py
             WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  endif()
  set_tests_properties(python.${name} PROPERTIES LABELS gl SKIP_RETURN_CODE 77)
endforeach()
set_tests_properties(python.sweep PROPERTIES PROCESSORS 2)
