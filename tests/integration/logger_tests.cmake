# hystloop-logger end to end (included by tests/integration/CMakeLists.txt): a probe
# publishes a known stream with a deliberate sequence gap; the logger records it; the
# files are read back with lcm::LogFile, replayed with lcm-logplayer, and the summary
# JSON checked with jq. udpm inside tools/netns-run (ttl=0).
add_executable(logger_probe ${CMAKE_CURRENT_LIST_DIR}/logger_probe.cpp)
target_link_libraries(logger_probe PRIVATE hystloop::lcm hystloop::warnings)
target_include_directories(logger_probe PRIVATE ${CMAKE_CURRENT_LIST_DIR}/..)

if(TARGET hystloop-logger)
  foreach(_script logger_record logger_rotation logger_cli)
    add_test(NAME ${_script}
      COMMAND ${_netns_run} -- ${CMAKE_CURRENT_LIST_DIR}/${_script}.sh
              $<TARGET_FILE:hystloop-logger> $<TARGET_FILE:logger_probe>)
    set_tests_properties(${_script} PROPERTIES LABELS integration TIMEOUT 60)
  endforeach()
  # A 2 MB tmpfs in a private mount namespace (needs root: skipped otherwise).
  add_test(NAME logger_full_disk
    COMMAND ${_netns_run} -- ${CMAKE_CURRENT_LIST_DIR}/logger_full_disk.sh
            $<TARGET_FILE:hystloop-logger> $<TARGET_FILE:logger_probe>)
  set_tests_properties(logger_full_disk PROPERTIES LABELS integration TIMEOUT 60 SKIP_RETURN_CODE 77)
endif()
