# Installs the build tree into a scratch prefix, then configures, builds and runs a
# consumer project that finds it with find_package(navtwin).
# Variables: BUILD_DIR, SOURCE_DIR, WORK_DIR. Each run works in its own folder below
# WORK_DIR (concurrent ctest runs never share one), removed when the check passes.
string(RANDOM LENGTH 10 run_id)
set(WORK_DIR ${WORK_DIR}/run_${run_id})
file(REMOVE_RECURSE ${WORK_DIR})
function(run)
  execute_process(COMMAND ${ARGV} RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "failed (${result}): ${ARGV}\n${out}\n${err}")
  endif()
endfunction()
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/install/consumer -B ${WORK_DIR}/build
    -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/consumer)
file(REMOVE_RECURSE ${WORK_DIR})
message(STATUS "navtwin installed and found by a consumer project")
