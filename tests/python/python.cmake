# pytest tests of the Python module (tests/python/*.py), labelled gl: they make OSMesa contexts.
# Under the sanitizers the module is instrumented, so Python (not built with ASan) gets the ASan
# and UBSan runtimes preloaded; leak checking is off for it (CPython leaves its own allocations at
# exit). The docs example runs the same code as the bindings test, slowly there: normal build only.
set(python_env "AG_TEST_TIME_SCALE=${AG_TEST_TIME_SCALE}")
if(AG_SANITIZE)
  execute_process(COMMAND ${CMAKE_CXX_COMPILER} -print-file-name=libasan.so
                  OUTPUT_VARIABLE asan_runtime OUTPUT_STRIP_TRAILING_WHITESPACE)
  execute_process(COMMAND ${CMAKE_CXX_COMPILER} -print-file-name=libubsan.so
                  OUTPUT_VARIABLE ubsan_runtime OUTPUT_STRIP_TRAILING_WHITESPACE)
  list(APPEND python_env "LD_PRELOAD=${asan_runtime} ${ubsan_runtime}"
       "ASAN_OPTIONS=detect_leaks=0:abort_on_error=1")
endif()
foreach(name bindings sweep docs_example plot_convergence)
  if(AG_SANITIZE AND name MATCHES "^(docs_example|plot_convergence)$")
    continue()
  endif()
  add_test(NAME python.${name}
           COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/python/run_pytest.sh ${AG_PYTHON}
                   $<TARGET_FILE:afterglow> ${PROJECT_BINARY_DIR}/python
                   ${CMAKE_CURRENT_SOURCE_DIR}/python/test_${name}.py
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(python.${name} PROPERTIES LABELS gl SKIP_RETURN_CODE 77)
  if(python_env)
    set_tests_properties(python.${name} PROPERTIES ENVIRONMENT "${python_env}")
  endif()
endforeach()
set_tests_properties(python.sweep PROPERTIES PROCESSORS 2)
