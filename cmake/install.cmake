# Install rules for the engine (issue 16): the library, its public headers, a CMake package
# (find_package(quadrant CONFIG) -> quadrant::quadrant) and a pkg-config file (quadrant.pc).
# Only the engine is installed; the adapters, scenes and tools are this repository's own.
include(CMakePackageConfigHelpers)

install(TARGETS quadrant EXPORT quadrantTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
# The distributed world's header is left out: quadrant_mpi (it needs MPI) is not installed.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/engine/include/quadrant
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} PATTERN distributed_world.h EXCLUDE)

set(_quadrant_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/quadrant)
install(EXPORT quadrantTargets NAMESPACE quadrant:: DESTINATION ${_quadrant_cmake_dir})
# The build tree as a package too (find_package with quadrant_DIR=<build dir>), without installing.
export(EXPORT quadrantTargets NAMESPACE quadrant:: FILE ${PROJECT_BINARY_DIR}/quadrantTargets.cmake)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/quadrantConfig.cmake.in
  ${PROJECT_BINARY_DIR}/quadrantConfig.cmake INSTALL_DESTINATION ${_quadrant_cmake_dir})
# 0.x: a minor version may change the API, so only the same major.minor is compatible.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/quadrantConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/quadrantConfig.cmake ${PROJECT_BINARY_DIR}/quadrantConfigVersion.cmake
        DESTINATION ${_quadrant_cmake_dir})

# pkg-config: the engine is a static library by default, so its thread library is in Libs (a
# static link needs it; Libs.private is only read with --static). QUADRANT_DOUBLE changes the
# public types, so a double build says so in Cflags.
set(QUADRANT_PC_CFLAGS "-std=c++20")
if(QUADRANT_DOUBLE)
  string(APPEND QUADRANT_PC_CFLAGS " -DQUADRANT_DOUBLE")
endif()
# Relocatable: prefix is found from the file's own place (pkg-config's ${pcfiledir}), so
# `cmake --install <build> --prefix P` gives a correct file under any P.
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
  set(QUADRANT_PC_PREFIX "${CMAKE_INSTALL_PREFIX}")
else()
  set(QUADRANT_PC_PREFIX "\${pcfiledir}/..")  # up from pkgconfig/ to the libdir
  string(REPLACE "/" ";" _parts "${CMAKE_INSTALL_LIBDIR}")
  foreach(_part IN LISTS _parts)
    string(APPEND QUADRANT_PC_PREFIX "/..")
  endforeach()
endif()
foreach(_dir LIBDIR INCLUDEDIR)
  if(IS_ABSOLUTE "${CMAKE_INSTALL_${_dir}}")
    set(QUADRANT_PC_${_dir} "${CMAKE_INSTALL_${_dir}}")
  else()
    set(QUADRANT_PC_${_dir} "\${prefix}/${CMAKE_INSTALL_${_dir}}")
  endif()
endforeach()
configure_file(${PROJECT_SOURCE_DIR}/cmake/quadrant.pc.in ${PROJECT_BINARY_DIR}/quadrant.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/quadrant.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
