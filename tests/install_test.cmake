# ctest script: cmake --install into WORK_DIR/prefix, then configure, build and
# run the consumer project against that prefix; with DEMO_DIR, build the demo
# the same way, as a standalone project (the embedding example), and run it.
file(REMOVE_RECURSE ${WORK_DIR})
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  message(STATUS "${out}")
endfunction()
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
# CONSUMER_FLAGS: the sanitizer flags of a sanitizer build, which its consumers must use too.
run(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=Release
    "-DCMAKE_CXX_FLAGS=${CONSUMER_FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${CONSUMER_FLAGS}")
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/consumer ${WORK_DIR}/prefix/share/facetrack/models/face_model.ftm)
if(NOT EXISTS ${WORK_DIR}/prefix/bin/facetrack)
  message(FATAL_ERROR "the facetrack CLI was not installed")
endif()
file(GLOB c_library ${WORK_DIR}/prefix/lib*/libfacetrack_c.so)
if(NOT c_library OR NOT EXISTS ${WORK_DIR}/prefix/include/facetrack/facetrack.h)
  message(FATAL_ERROR "the C API (libfacetrack_c.so, facetrack/facetrack.h) was not installed")
endif()
if(DEMO_DIR)
  run(${CMAKE_COMMAND} -S ${DEMO_DIR} -B ${WORK_DIR}/demo -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=Release
      "-DCMAKE_CXX_FLAGS=-Wall -Wextra -Werror")
  run(${CMAKE_COMMAND} --build ${WORK_DIR}/demo -j2)
  run(${WORK_DIR}/demo/facetrack_demo --help)
endif()
