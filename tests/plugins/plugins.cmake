# Test plugins (tests/plugin_test.cpp): the example's seal leakage built in
# the tree, plugins that must be refused, and the out-of-tree example built
# against an installed pneumo (ctest fixture plugin_example).
set(PNEUMO_TEST_PLUGIN_DIR ${CMAKE_CURRENT_BINARY_DIR}/plugins)
pneumo_add_plugin(pneumo_test_seal_leakage ${PROJECT_SOURCE_DIR}/examples/custom_component/seal_leakage.cpp)
set_target_properties(pneumo_test_seal_leakage PROPERTIES
  OUTPUT_NAME seal_leakage LIBRARY_OUTPUT_DIRECTORY ${PNEUMO_TEST_PLUGIN_DIR})
foreach(defect IN ITEMS 1 2 3 4 5 6 7 8)
  pneumo_add_plugin(pneumo_test_defective_${defect} ${CMAKE_CURRENT_SOURCE_DIR}/plugins/defective_plugin.cpp)
  target_compile_definitions(pneumo_test_defective_${defect} PRIVATE PNEUMO_TEST_DEFECT=${defect})
  set_target_properties(pneumo_test_defective_${defect} PROPERTIES
    OUTPUT_NAME defective_${defect} LIBRARY_OUTPUT_DIRECTORY ${PNEUMO_TEST_PLUGIN_DIR})
  add_dependencies(pneumo_tests pneumo_test_defective_${defect})
endforeach()
add_library(pneumo_test_not_a_plugin MODULE ${CMAKE_CURRENT_SOURCE_DIR}/plugins/not_a_plugin.cpp)
set_target_properties(pneumo_test_not_a_plugin PROPERTIES
  PREFIX "" OUTPUT_NAME not_a_plugin LIBRARY_OUTPUT_DIRECTORY ${PNEUMO_TEST_PLUGIN_DIR})
add_dependencies(pneumo_tests pneumo_test_seal_leakage pneumo_test_not_a_plugin)
target_compile_definitions(pneumo_tests PRIVATE PNEUMO_TEST_PLUGIN_DIR="${PNEUMO_TEST_PLUGIN_DIR}")

# The out-of-tree example: install this build into a prefix, configure and
# build examples/custom_component against it with find_package(pneumo)
# (fixture setup, once), then run the installed `pneumo` on the example's
# netlist and the example's own test-kit tests.
set(PNEUMO_EXAMPLE_WORK ${CMAKE_CURRENT_BINARY_DIR}/plugin_example)
add_test(NAME plugin_example_install_and_build
  COMMAND ${CMAKE_COMMAND}
    -DBUILD_DIR=${PROJECT_BINARY_DIR}
    -DEXAMPLE_DIR=${PROJECT_SOURCE_DIR}/examples/custom_component
    -DWORK=${PNEUMO_EXAMPLE_WORK}
    -DGENERATOR=${CMAKE_GENERATOR}
    -P ${CMAKE_CURRENT_SOURCE_DIR}/plugins/install_and_build.cmake)
set_tests_properties(plugin_example_install_and_build PROPERTIES FIXTURES_SETUP plugin_example TIMEOUT 900)

add_executable(pneumo_plugin_example_tests ${CMAKE_CURRENT_SOURCE_DIR}/plugins/example_test.cpp)
target_link_libraries(pneumo_plugin_example_tests PRIVATE pneumo_framework GTest::gtest_main)
target_compile_definitions(pneumo_plugin_example_tests PRIVATE PNEUMO_EXAMPLE_WORK="${PNEUMO_EXAMPLE_WORK}")
gtest_discover_tests(pneumo_plugin_example_tests DISCOVERY_TIMEOUT 60
  PROPERTIES FIXTURES_REQUIRED plugin_example)
add_test(NAME plugin_example_author_tests COMMAND ${PNEUMO_EXAMPLE_WORK}/build/seal_leakage_test)
set_tests_properties(plugin_example_author_tests PROPERTIES FIXTURES_REQUIRED plugin_example)
