include(GoogleTest)

# How long a multi-rank test may take before CTest kills it: a hang fails in seconds, not at
# CI's limit.
set(DFBWALL_MPI_TEST_TIMEOUT 60 CACHE STRING "Seconds before a multi-rank test counts as hung")

# add_unit_test(NAME SOURCES... LIBS... [LABELS ...])
# A plain GoogleTest binary; each TEST becomes its own CTest test, labelled 'unit'.
function(add_unit_test name)
  cmake_parse_arguments(T "" "" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${T_SOURCES})
  target_link_libraries(${name} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main dfbwall_warnings)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR})
  # Tests read configs and fixtures from the source tree.
  target_compile_definitions(${name} PRIVATE DFBWALL_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  gtest_discover_tests(${name} PROPERTIES TIMEOUT 120 DISCOVERY_TIMEOUT 30)
  # gtest_discover_tests flattens a list given in PROPERTIES (LABELS "unit;wall" becomes the
  # label "unit" and a stray property "wall"), so the labels are set by a script CTest runs
  # after it has read the discovered tests.
  set(labels unit ${T_LABELS})
  set(script ${CMAKE_CURRENT_BINARY_DIR}/${name}_labels.cmake)
  file(WRITE ${script}
       "foreach(t IN LISTS ${name}_TESTS)\n"
       "  set_tests_properties(\${t} PROPERTIES LABELS \"${labels}\")\n"
       "endforeach()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${script})
endfunction()

# add_mpi_test(NAME TARGET NPROCS [ARGS ...] [LABELS ...] [TIMEOUT s])
# Runs TARGET on NPROCS real ranks through mpiexec, labelled 'mpi'.
function(add_mpi_test name target nprocs)
  cmake_parse_arguments(T "" "TIMEOUT" "ARGS;LABELS" ${ARGN})
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT ${DFBWALL_MPI_TEST_TIMEOUT})
  endif()
  add_test(NAME ${name}
           COMMAND ${MPIEXEC_EXECUTABLE} ${MPIEXEC_NUMPROC_FLAG} ${nprocs} --oversubscribe
                   --bind-to none ${MPIEXEC_PREFLAGS} $<TARGET_FILE:${target}> ${T_ARGS}
                   ${MPIEXEC_POSTFLAGS})
  set_tests_properties(${name} PROPERTIES
    LABELS "mpi;${T_LABELS}"
    TIMEOUT ${T_TIMEOUT}
    ENVIRONMENT "OMPI_ALLOW_RUN_AS_ROOT=1;OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1;OMPI_MCA_rmaps_base_oversubscribe=1")
endfunction()
