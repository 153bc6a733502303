# dynamap_target_defaults(<target>): warnings as errors and sanitizers, applied PRIVATE to our
# own targets only, so third-party headers never break the build.
if(DYNAMAP_SANITIZE AND DYNAMAP_TSAN)
  message(FATAL_ERROR "DYNAMAP_SANITIZE (ASan+UBSan) and DYNAMAP_TSAN cannot be combined")
endif()
if(DYNAMAP_FUZZ AND NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
  message(FATAL_ERROR "DYNAMAP_FUZZ needs clang (libFuzzer): -DCMAKE_CXX_COMPILER=clang++")
endif()

function(dynamap_target_defaults target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Werror
                                           -Wno-error=deprecated-declarations)
  if(DYNAMAP_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined
                                             -fno-sanitize-recover=undefined
                                             -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
    if(CMAKE_CXX_COMPILER_ID MATCHES "Clang" AND target STREQUAL "dynamap_backend_vdb_tsdf")
      # TBB headers (OpenVDB's accessor registry): see scripts/ubsan_ignore.txt.
      target_compile_options(${target} PRIVATE
        -fsanitize-ignorelist=${PROJECT_SOURCE_DIR}/scripts/ubsan_ignore.txt)
    endif()
  endif()
  if(DYNAMAP_TSAN)
    target_compile_options(${target} PRIVATE -fsanitize=thread -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=thread)
  endif()
  if(DYNAMAP_FUZZ AND DYNAMAP_FUZZ_COVERAGE)
    # Coverage feedback for libFuzzer from our libraries; the fuzzers themselves link
    # -fsanitize=fuzzer (fuzz/CMakeLists.txt).
    target_compile_options(${target} PRIVATE -fsanitize=fuzzer-no-link)
  endif()
endfunction()

# Sanitizer flags must reach every object that links the runtime (executables, plugins).
if(DYNAMAP_SANITIZE)
  add_link_options(-fsanitize=address,undefined)
endif()
if(DYNAMAP_TSAN)
  add_link_options(-fsanitize=thread)
endif()
