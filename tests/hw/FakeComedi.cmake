# The fake comedi card (fake_comedi.hpp), for tests/hw and bench/comedi_benchmark.cpp.
include_guard(GLOBAL)

# Linked into test programs: the program itself defines comedilib's calls, which ELF symbol lookup
# prefers to libcomedi.so.0's (an OBJECT library, so every definition is linked, used or not).
add_library(hystloop_fake_comedi OBJECT ${CMAKE_CURRENT_LIST_DIR}/fake_comedi.cpp)
target_include_directories(hystloop_fake_comedi PUBLIC ${CMAKE_CURRENT_LIST_DIR})
target_link_libraries(hystloop_fake_comedi PRIVATE hystloop::warnings)

# The same fake as a drop-in libcomedi.so.0 (comedilib's symbol versions) for running the real
# hystloop-bridge binary: LD_LIBRARY_PATH=<this directory>.
set(HYSTLOOP_FAKE_LIBCOMEDI_DIR ${PROJECT_BINARY_DIR}/tests/hw/fake_libcomedi)
add_library(hystloop_fake_libcomedi SHARED ${CMAKE_CURRENT_LIST_DIR}/fake_comedi.cpp)
set_target_properties(hystloop_fake_libcomedi PROPERTIES
  OUTPUT_NAME comedi SOVERSION 0 LIBRARY_OUTPUT_DIRECTORY ${HYSTLOOP_FAKE_LIBCOMEDI_DIR}
  LINK_DEPENDS ${CMAKE_CURRENT_LIST_DIR}/fake_comedi.map)
target_link_options(hystloop_fake_libcomedi PRIVATE -Wl,--version-script=${CMAKE_CURRENT_LIST_DIR}/fake_comedi.map)
target_link_libraries(hystloop_fake_libcomedi PRIVATE hystloop::warnings)
