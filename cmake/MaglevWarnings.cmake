# Strict warnings, as errors, on our own code only (never on Eigen or system
# headers, which are included as SYSTEM).
function(maglev_set_warnings target)
  set(_warn
    -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wsign-conversion
    -Wdouble-promotion -Wcast-align -Wnull-dereference -Wformat=2
    -Wimplicit-fallthrough -Wmissing-declarations -Werror)
  get_target_property(_type ${target} TYPE)
  if(_type STREQUAL "INTERFACE_LIBRARY")
    return()
  endif()
  # GCC 12's ASan instrumentation makes -Wmaybe-uninitialized fire inside
  # libstdc++ (std::function in <regex>, ...): known false positives, so that
  # one warning is off in the sanitizer build only (the host build keeps it).
  if(MAGLEV_SANITIZE)
    list(APPEND _warn -Wno-maybe-uninitialized)
  endif()
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:${_warn} -Wold-style-cast -Wnon-virtual-dtor>
    $<$<COMPILE_LANGUAGE:C>:${_warn}>)
endfunction()
