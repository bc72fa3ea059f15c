# Driver of the downstream tests (cmake -P): with MODE=install, install the flexmor build tree
# FLEXMOR_BUILD_DIR into a prefix under WORK_DIR, then configure, build and run the project
# in this folder against it (find_package); with MODE=subdirectory, the project adds the
# flexmor sources FLEXMOR_SOURCE_DIR with add_subdirectory instead. Fails on any step.
foreach(var MODE WORK_DIR FLEXMOR_SOURCE_DIR BUILD_TYPE Fortran_COMPILER C_COMPILER GENERATOR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run.cmake: -D${var}=... is missing")
  endif()
endforeach()

function(step what)
  string(TIMESTAMP t0 "%s")
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  string(TIMESTAMP t1 "%s")
  math(EXPR dt "${t1} - ${t0}")
  message(STATUS "downstream (${MODE}): ${what}: exit ${rc}, ${dt} s")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "downstream (${MODE}): ${what} failed")
  endif()
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
set(build ${WORK_DIR}/build)
# The same compilers as flexmor's build: .mod files are compiler-specific.
set(config_args -G ${GENERATOR} -DCMAKE_BUILD_TYPE=${BUILD_TYPE}
    -DCMAKE_Fortran_COMPILER=${Fortran_COMPILER})
if(MODE STREQUAL "install")
  if(NOT DEFINED FLEXMOR_BUILD_DIR)
    message(FATAL_ERROR "run.cmake: -DFLEXMOR_BUILD_DIR=... is missing")
  endif()
  set(prefix ${WORK_DIR}/prefix)
  step("install into ${prefix}" ${CMAKE_COMMAND} --install ${FLEXMOR_BUILD_DIR}
       --prefix ${prefix} --config ${BUILD_TYPE})
  step("configure" ${CMAKE_COMMAND} -S ${CMAKE_CURRENT_LIST_DIR} -B ${build} ${config_args}
       -DCMAKE_C_COMPILER=${C_COMPILER} -DCMAKE_PREFIX_PATH=${prefix})
elseif(MODE STREQUAL "subdirectory")
  step("configure" ${CMAKE_COMMAND} -S ${CMAKE_CURRENT_LIST_DIR} -B ${build} ${config_args}
       -DCMAKE_C_COMPILER=${C_COMPILER} -DFLEXMOR_SOURCE_DIR=${FLEXMOR_SOURCE_DIR})
else()
  message(FATAL_ERROR "run.cmake: MODE is 'install' or 'subdirectory', not '${MODE}'")
endif()
step("build" ${CMAKE_COMMAND} --build ${build} -j 2)
step("run" ${build}/downstream ${WORK_DIR}/downstream.h5)
step("run the C example" ${build}/pd_rigid_link ${CMAKE_CURRENT_LIST_DIR}/../../examples/c)
