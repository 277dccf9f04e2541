# find_package(Afterglow): install into the build folder, build tests/install against it, run it.
if(NOT AG_SANITIZE)
  add_test(NAME install.find_package
           COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/install/install_test.sh ${PROJECT_BINARY_DIR}
                   ${AG_PYTHON})
  set_tests_properties(install.find_package PROPERTIES LABELS gl SKIP_RETURN_CODE 77
                       TIMEOUT 300)
endif()
