# `cmake --install build [--prefix P]`: the libraries, the API's headers, a CMake package and the
# Python module, so a program does find_package(dfbwall) and links dfbwall::dfbwall (C++,
# examples/insitu), dfbwall::c (the C API in libdfbwall.so, examples/insitu-c) or dfbwall::fortran
# (the Fortran module over it, examples/insitu-f90, when built).
# The libraries are static; their dependencies come back through find_dependency in
# dfbwallConfig.cmake (cmake/dfbwallConfig.cmake.in).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(DFBWALL_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/dfbwall)
set(DFBWALL_INSTALLED_TARGETS dfbwall_api dfbwall_c)
if(TARGET dfbwall_fortran)
  list(APPEND DFBWALL_INSTALLED_TARGETS dfbwall_fortran)
endif()
install(TARGETS ${DFBWALL_INSTALLED_TARGETS} base messaging dfb renderers wall runtime wall_glfw dfbwall_warnings
  EXPORT dfbwallTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION include)
# The public header only: <dfbwall/DataDistributed.h> (the tests' api/SessionTesting.h stays out).
install(FILES ${PROJECT_SOURCE_DIR}/api/DataDistributed.h ${PROJECT_SOURCE_DIR}/bindings/c/dfbwall.h
  DESTINATION include/dfbwall)
install(EXPORT dfbwallTargets NAMESPACE dfbwall:: DESTINATION ${DFBWALL_CMAKE_DIR})
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/dfbwallConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/dfbwallConfig.cmake INSTALL_DESTINATION ${DFBWALL_CMAKE_DIR})
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/dfbwallConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/dfbwallConfig.cmake
              ${CMAKE_CURRENT_BINARY_DIR}/dfbwallConfigVersion.cmake
        DESTINATION ${DFBWALL_CMAKE_DIR})
