# hystloop::warnings — an interface target every project target links, so the
# warning policy and the sanitizer flags live in one place.
add_library(hystloop_warnings INTERFACE)
add_library(hystloop::warnings ALIAS hystloop_warnings)
target_compile_options(hystloop_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
  -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual
  -Wnull-dereference -Wdouble-promotion -Wimplicit-fallthrough)
if(HYSTLOOP_WERROR)
  target_compile_options(hystloop_warnings INTERFACE -Werror)
endif()
if(HYSTLOOP_BUILD_FUZZERS)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "HYSTLOOP_BUILD_FUZZERS needs clang (libFuzzer): configure with CXX=clang++")
  endif()
  # Every library is instrumented for coverage and checked by ASan + UBSan; the fuzz targets link
  # libFuzzer's main (tests/fuzz/CMakeLists.txt).
  target_compile_options(hystloop_warnings INTERFACE
    -fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
  target_link_options(hystloop_warnings INTERFACE -fsanitize=address,undefined)
endif()
if(HYSTLOOP_SANITIZE)
  target_compile_options(hystloop_warnings INTERFACE
    -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
  target_link_options(hystloop_warnings INTERFACE -fsanitize=address,undefined)
endif()

# Third-party headers are included as SYSTEM so their warnings do not fail our build.
function(hystloop_target NAME)
  target_link_libraries(${NAME} PRIVATE hystloop::warnings)
endfunction()
