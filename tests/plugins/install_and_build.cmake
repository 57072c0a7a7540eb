# ctest fixture: cmake --install the pneumo build into WORK/prefix, then
# configure and build the out-of-tree example against that prefix only.
foreach(v BUILD_DIR EXAMPLE_DIR WORK GENERATOR)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "install_and_build.cmake: -D${v}=... missing")
  endif()
endforeach()

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "failed (${rc}): ${cmd}\n${out}\n${err}")
  endif()
  set(run_output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK})
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK}/prefix)
run(${CMAKE_COMMAND} -S ${EXAMPLE_DIR} -B ${WORK}/build -G ${GENERATOR}
    -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_PREFIX_PATH=${WORK}/prefix
    -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
# The package must come from the prefix just installed, not from elsewhere.
file(STRINGS ${WORK}/build/CMakeCache.txt pneumo_dir REGEX "^pneumo_DIR:")
string(FIND "${pneumo_dir}" "${WORK}/prefix/" at)
if(NOT at GREATER -1)
  message(FATAL_ERROR "the example found pneumo outside ${WORK}/prefix: ${pneumo_dir}")
endif()
run(${CMAKE_COMMAND} --build ${WORK}/build -j2)
foreach(f ${WORK}/build/seal_leakage.so ${WORK}/build/seal_leakage.yaml ${WORK}/build/seal_leakage_test
          ${WORK}/prefix/bin/pneumo)
  if(NOT EXISTS ${f})
    message(FATAL_ERROR "missing after the build: ${f}")
  endif()
endforeach()
message(STATUS "installed pneumo into ${WORK}/prefix and built the example in ${WORK}/build")
