# hystloop-reidentifier end to end (included by tests/integration/CMakeLists.txt): a test
# publisher streams MEM data at 10 kHz, the re-identifier must publish a refit close to the
# truth, and must publish nothing for garbage; one for axis y must fit y's ticks of two-axis
# blocks as "reidentifier-y"; plus --help, bad configuration (exit 2 naming the field) and
# SIGTERM (exit 0 within 1 s). udpm inside tools/netns-run (ttl=0).
add_executable(reident_stream ${CMAKE_CURRENT_LIST_DIR}/reident_stream.cpp)
target_link_libraries(reident_stream PRIVATE hystloop::lcm hystloop::models hystloop::warnings)
target_include_directories(reident_stream PRIVATE ${CMAKE_CURRENT_LIST_DIR}/..)

if(TARGET hystloop-reidentifier)
  foreach(_case cli good invalid garbage axis)
    add_test(NAME reident_${_case}
      COMMAND ${_netns_run} -- ${CMAKE_CURRENT_LIST_DIR}/reident_run.sh ${_case}
              $<TARGET_FILE:hystloop-reidentifier> $<TARGET_FILE:reident_stream> ${PROJECT_SOURCE_DIR})
    # A 10 kHz stream and a real-time service: not beside a live loop (replay_tests.cmake says why).
    set_tests_properties(reident_${_case} PROPERTIES LABELS integration TIMEOUT 60 RESOURCE_LOCK hystloop_live_loop)
  endforeach()
endif()
