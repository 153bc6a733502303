# Unity builds (cmake -DCMAKE_UNITY_BUILD=ON; the sanitizer builds of scripts/sanitize.sh): each
# target's .cpp files compile in batches of 8, so OpenCV, Eigen, Ceres, OpenVDB and GoogleTest
# headers are parsed once a batch, not once a file (the 8 files of core's 4th batch: 76.9 s
# of CPU one by one, 36.3 s as one, clang ASan). A file whose file-local names (anonymous
# namespace) clash with another file of its target compiles alone, listed here.
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
                    dynamic/fusion_time_test.cpp dynamic/fusion_anchor_test.cpp
                    loop/tracker_loop_test.cpp)
