# `cmake --install <build> [--prefix DIR]`: headers, the libraries (dynamap::core, ::mapping,
# ::system), the backend plugins in <libdir>/dynamap (where dynamap::system looks for them), the
# `dynamap` program, and a CMake package: find_package(dynamap) + dynamap::system.
include(CMakePackageConfigHelpers)

set(DYNAMAP_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/dynamap)
set(DYNAMAP_INSTALL_PLUGINDIR ${CMAKE_INSTALL_LIBDIR}/dynamap)

set_target_properties(dynamap_core dynamap_mapping dynamap_system PROPERTIES
  INSTALL_RPATH "$ORIGIN" INSTALL_RPATH_USE_LINK_PATH TRUE)
install(TARGETS dynamap_core dynamap_mapping dynamap_system EXPORT dynamapTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
foreach(dir core/include mapping/include system/include)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}/dynamap DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endforeach()

get_property(dynamap_backend_targets GLOBAL PROPERTY DYNAMAP_BACKEND_TARGETS)
if(dynamap_backend_targets)
  set_target_properties(${dynamap_backend_targets} PROPERTIES
    INSTALL_RPATH "$ORIGIN/.." INSTALL_RPATH_USE_LINK_PATH TRUE)
  install(TARGETS ${dynamap_backend_targets} LIBRARY DESTINATION ${DYNAMAP_INSTALL_PLUGINDIR})
endif()

set_target_properties(dynamap PROPERTIES
  INSTALL_RPATH "$ORIGIN/../${CMAKE_INSTALL_LIBDIR}" INSTALL_RPATH_USE_LINK_PATH TRUE)
install(TARGETS dynamap dynamap_io dynamap_eval
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
set_target_properties(dynamap_io dynamap_eval PROPERTIES
  INSTALL_RPATH "$ORIGIN" INSTALL_RPATH_USE_LINK_PATH TRUE)

install(EXPORT dynamapTargets NAMESPACE dynamap:: DESTINATION ${DYNAMAP_INSTALL_CMAKEDIR})
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/dynamapConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/dynamapConfig.cmake INSTALL_DESTINATION ${DYNAMAP_INSTALL_CMAKEDIR})
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/dynamapConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/dynamapConfig.cmake
              ${CMAKE_CURRENT_BINARY_DIR}/dynamapConfigVersion.cmake
        DESTINATION ${DYNAMAP_INSTALL_CMAKEDIR})
