# ctest "consumer.installed_package": cmake --install the build tree into BIN_DIR/consumer-test,
# build tests/consumer against it with find_package(dynamap), run it on the first FRAMES teddy
# frames and compare with `dynamap run` on the same frames.
# -D: BIN_DIR SOURCE_DIR CLI SEQUENCE GENERATOR FRAMES
if(NOT EXISTS "${SEQUENCE}/rgb.txt")
  message("consumer test skipped: ${SEQUENCE} not found")
  return()
endif()
set(work ${BIN_DIR}/consumer-test)
file(REMOVE_RECURSE ${work})
set(config ${SOURCE_DIR}/config/default.yaml)

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${out}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${err}")
  endif()
endfunction()

run("cmake --install" ${CMAKE_COMMAND} --install ${BIN_DIR} --prefix ${work}/install)
run("configure consumer" ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/consumer -B ${work}/build
    -G ${GENERATOR} -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${work}/install)
run("build consumer" ${CMAKE_COMMAND} --build ${work}/build)
run("dynamap run" ${CLI} run --sequence ${SEQUENCE} --out ${work}/cli --quiet --config ${config}
    --set dataset.max_frames=${FRAMES})
run("consumer" ${work}/build/consumer ${SEQUENCE} ${config} ${FRAMES} ${work}/cli/trajectory.txt)
