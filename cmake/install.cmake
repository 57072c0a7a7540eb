# Install rules and the CMake package: headers under include/pneumo
# (framework/..., components/...), the shared libraries, the `pneumo`
# command, and lib/cmake/pneumo with pneumoConfig.cmake, its version file
# and the exported targets pneumo::framework, pneumo::components,
# pneumo::testkit and pneumo::pneumo, plus pneumo_add_plugin().
include(CMakePackageConfigHelpers)

set(PNEUMO_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/pneumo)

foreach(lib pneumo_framework pneumo_components pneumo_testkit)
  string(REPLACE "pneumo_" "" short ${lib})
  add_library(pneumo::${short} ALIAS ${lib})
  set_target_properties(${lib} PROPERTIES
    EXPORT_NAME ${short}
    VERSION ${PROJECT_VERSION}
    SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR}
    INSTALL_RPATH "$ORIGIN")
endforeach()
file(RELATIVE_PATH PNEUMO_BIN_TO_LIB /${CMAKE_INSTALL_BINDIR} /${CMAKE_INSTALL_LIBDIR})
set_target_properties(pneumo PROPERTIES INSTALL_RPATH "$ORIGIN/${PNEUMO_BIN_TO_LIB}")

install(TARGETS pneumo_framework pneumo_components pneumo_testkit pneumo
  EXPORT pneumoTargets
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
# The FMU runtime, beside the libraries: pneumo export-fmu looks for it there.
install(TARGETS pneumo_fmu LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(DIRECTORY framework components
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/pneumo
  FILES_MATCHING PATTERN "*.hpp" PATTERN "cli" EXCLUDE)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/generated/framework/core/version.hpp
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/pneumo/framework/core)
install(EXPORT pneumoTargets NAMESPACE pneumo:: DESTINATION ${PNEUMO_INSTALL_CMAKEDIR})

configure_package_config_file(cmake/pneumoConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/pneumoConfig.cmake
  INSTALL_DESTINATION ${PNEUMO_INSTALL_CMAKEDIR})
# Plugins are checked for the exact pneumo version at load time; the
# package accepts requests of the same major.minor.
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/pneumoConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES
  ${CMAKE_CURRENT_BINARY_DIR}/pneumoConfig.cmake
  ${CMAKE_CURRENT_BINARY_DIR}/pneumoConfigVersion.cmake
  cmake/pneumoPlugin.cmake
  DESTINATION ${PNEUMO_INSTALL_CMAKEDIR})

include(cmake/pneumoPlugin.cmake)
