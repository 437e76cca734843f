# Installs the built tree into a scratch prefix, builds tests/install_consumer against it with find_package,
# runs it, and runs the installed strata executable. Invoked by CTest (see tests/CMakeLists.txt).
# Inputs: BUILD_DIR, SOURCE_DIR, WORK_DIR.
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")

function(run_step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "step failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

run_step(${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${prefix}")
foreach(f bin/strata lib/cmake/Strata/StrataConfig.cmake include/strata/io/hanim_loader.h share/strata/default_skeleton.x3d
        include/strata/nav/navmesh.h share/strata/scenarios/bottleneck.json)
  if(NOT EXISTS "${prefix}/${f}")
    file(GLOB_RECURSE found RELATIVE "${prefix}" "${prefix}/*")
    message(FATAL_ERROR "install is missing ${f}; it has: ${found}")
  endif()
endforeach()
run_step(${CMAKE_COMMAND} -S "${SOURCE_DIR}/tests/install_consumer" -B "${WORK_DIR}/build" -G Ninja
         -DCMAKE_BUILD_TYPE=Release "-DCMAKE_PREFIX_PATH=${prefix}")
run_step(${CMAKE_COMMAND} --build "${WORK_DIR}/build")
run_step("${WORK_DIR}/build/consumer")
if(NOT step_output MATCHES "25 joints, 4 walkers" OR NOT step_output MATCHES "bottleneck passable")
  message(FATAL_ERROR "consumer printed: ${step_output}")
endif()
run_step("${prefix}/bin/strata" info "${prefix}/share/strata/default_skeleton.x3d")
if(NOT step_output MATCHES "joints: +25")
  message(FATAL_ERROR "installed strata info printed: ${step_output}")
endif()
message(STATUS "install consumer: OK")
