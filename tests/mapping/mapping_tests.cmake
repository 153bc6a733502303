# Extra wiring of dynamap_mapping_tests (included from tests/CMakeLists.txt): the libraries whose
# own loaders read the exports back, the plugins themselves, and the out-of-tree example plugin.
add_dependencies(dynamap_mapping_tests dynamap_backends)
if(DYNAMAP_WITH_PCL)
  target_link_libraries(dynamap_mapping_tests PRIVATE ${PCL_LIBRARIES})
  target_include_directories(dynamap_mapping_tests SYSTEM PRIVATE ${PCL_INCLUDE_DIRS})
  target_compile_definitions(dynamap_mapping_tests PRIVATE DYNAMAP_TEST_WITH_PCL)
endif()
if(DYNAMAP_WITH_OPENVDB)
  target_link_libraries(dynamap_mapping_tests PRIVATE OpenVDB::openvdb)
  target_compile_definitions(dynamap_mapping_tests PRIVATE DYNAMAP_TEST_WITH_OPENVDB)
endif()
if(DYNAMAP_WITH_OCTOMAP)
  target_link_libraries(dynamap_mapping_tests PRIVATE ${OCTOMAP_LIBRARIES})
  target_include_directories(dynamap_mapping_tests SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS})
  target_compile_definitions(dynamap_mapping_tests PRIVATE DYNAMAP_TEST_WITH_OCTOMAP)
endif()

# The example plugin, compiled like a third party would: one .cpp, the public headers, the
# compiler directly (no dynamap target involved), into a folder the registry does not scan by
# default.
set(example_dir ${CMAKE_BINARY_DIR}/example_plugins)
set(example_so ${example_dir}/libdynamap_backend_example.so)
set(example_src ${CMAKE_CURRENT_SOURCE_DIR}/mapping/example_plugin/example_backend.cpp)
set(example_includes -I${PROJECT_SOURCE_DIR}/mapping/include -I${PROJECT_SOURCE_DIR}/core/include)
foreach(dir ${EIGEN3_INCLUDE_DIRS} ${OpenCV_INCLUDE_DIRS})
  list(APPEND example_includes -isystem ${dir})
endforeach()
add_custom_command(
  OUTPUT ${example_so}
  COMMAND ${CMAKE_COMMAND} -E make_directory ${example_dir}
  COMMAND ${CMAKE_CXX_COMPILER} -std=c++17 -O2 -fPIC -shared -Wall -Wextra -Werror
          ${example_includes} ${example_src} -o ${example_so} -MD -MF ${example_so}.d
  DEPENDS ${example_src}
  DEPFILE ${example_so}.d  # rebuilt when a public header it includes changes (the plugin ABI)
  COMMENT "Building the out-of-tree example backend plugin"
  VERBATIM)
add_custom_target(dynamap_example_plugin DEPENDS ${example_so})
add_dependencies(dynamap_mapping_tests dynamap_example_plugin)
target_compile_definitions(dynamap_mapping_tests PRIVATE
  DYNAMAP_EXAMPLE_PLUGIN_DIR="${example_dir}")

# The backends' own helpers under test (header-only: keyframe_voxels.hpp).
target_include_directories(dynamap_mapping_tests PRIVATE ${PROJECT_SOURCE_DIR}/plugins/common
                                                         ${PROJECT_SOURCE_DIR}/plugins/pcl_voxel)
