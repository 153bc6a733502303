# dynamap_target_defaults(<target>): warnings as errors and sanitizers, applied PRIVATE to our
# own targets only, so third-party headers never break the build.
function(dynamap_target_defaults target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Werror
                                           -Wno-error=deprecated-declarations)
  if(DYNAMAP_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined
                                             -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()

# Sanitizer flags must reach every object that links the runtime (executables, plugins).
if(DYNAMAP_SANITIZE)
  add_link_options(-fsanitize=address,undefined)
endif()
