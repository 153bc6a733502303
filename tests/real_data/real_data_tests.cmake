# ctest -L real_data: tests/real_data/bands.py check CASE for every case it lists.
set(bands_py ${CMAKE_CURRENT_LIST_DIR}/bands.py)
execute_process(COMMAND /usr/bin/python3 ${bands_py} list OUTPUT_VARIABLE cases
                RESULT_VARIABLE listed OUTPUT_STRIP_TRAILING_WHITESPACE)
if(NOT listed EQUAL 0)
  message(FATAL_ERROR "tests/real_data/bands.py list failed (needs /usr/bin/python3)")
endif()
string(REPLACE "\n" ";" cases "${cases}")
foreach(case IN LISTS cases)
  add_test(NAME real_data.${case}
           COMMAND /usr/bin/python3 ${bands_py} check ${case} --dynamap $<TARGET_FILE:dynamap>
                   --work ${PROJECT_BINARY_DIR}/real_data)
  set_tests_properties(real_data.${case} PROPERTIES LABELS real_data TIMEOUT 900
                       COST 60)  # whole runs start first (tests/CMakeLists.txt, COST)
endforeach()
add_test(NAME real_data.band_logic COMMAND /usr/bin/python3 -m pytest -q
         ${CMAKE_CURRENT_LIST_DIR}/test_bands.py)
set_tests_properties(real_data.band_logic PROPERTIES LABELS unit)
# Save and reload on real data (issue 47's criterion): run 2 plays the sequence backward in
# run 1's map.
foreach(case teddy bonn_crowd_slice)
  add_test(NAME real_data.reload_${case}
           COMMAND /usr/bin/python3 ${CMAKE_CURRENT_LIST_DIR}/reload_check.py ${case}
                   --dynamap $<TARGET_FILE:dynamap> --work ${PROJECT_BINARY_DIR}/real_data_reload)
  set_tests_properties(real_data.reload_${case} PROPERTIES LABELS real_data TIMEOUT 600 COST 60)
endforeach()
# A span whose run 2 lost the map before the held-back objects were tracked in it (25 cm at
# 0c16d6e).
add_test(NAME real_data.reload_teddy_dyn_crowd_dev_0_180
         COMMAND /usr/bin/python3 ${CMAKE_CURRENT_LIST_DIR}/reload_check.py teddy_dyn_crowd_dev
                 --frames 0,180 --dynamap $<TARGET_FILE:dynamap>
                 --work ${PROJECT_BINARY_DIR}/real_data_reload)
set_tests_properties(real_data.reload_teddy_dyn_crowd_dev_0_180
                     PROPERTIES LABELS real_data TIMEOUT 600 COST 60)
