# Unity builds (CMAKE_UNITY_BUILD, ON by default: CMakeLists.txt): each target's .cpp files
# compile in batches of 8, so OpenCV, Eigen, Ceres, OpenVDB and GoogleTest headers are parsed
# once a batch, not once a file (the 8 files of core's 4th batch: 76.9 s
# of CPU one by one, 36.3 s as one, clang ASan). A file whose file-local names (anonymous
# namespace) clash with, or would overload, those of another file of its target compiles
# alone, listed here (found by building all of them; a clash is a compile error).
if(NOT CMAKE_UNITY_BUILD)
  return()
endif()
function(dynamap_unity_alone dir)
  list(TRANSFORM ARGN PREPEND ${PROJECT_SOURCE_DIR}/${dir}/ OUTPUT_VARIABLE files)
  set_source_files_properties(${files} DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}
                              PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON)
endfunction()
dynamap_unity_alone(mapping src/mapping_worker.cpp)
dynamap_unity_alone(tests io/tum_dataset_test.cpp tracking/local_ba_thread_test.cpp
                    tracking/crowded_keyframes_test.cpp
                    loop/tracker_loop_test.cpp system/system_test.cpp system/saved_map_test.cpp
                    mapping/visibility_brief_test.cpp mapping/visibility_test.cpp
                    mapping/mask_lookahead_test.cpp dynamic/fusion_identity_test.cpp
                    dynamic/fusion_time_test.cpp dynamic/rigid_prior_test.cpp
                    dynamic/fusion_anchor_test.cpp dynamic/support_planes_test.cpp
                    dynamic/mover_tracks_test.cpp)
