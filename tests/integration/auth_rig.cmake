# The authenticated rig (README "Authenticated rig"), end to end over udpm inside tools/netns-run:
# a keyed bridge + compensator, a foreign keyless publisher (hystloop-ctl, auth_probe), a captured
# signed command block replayed later, a keyed logger and hystloop-report on its record. Included by tests/integration/CMakeLists.txt.
add_executable(auth_probe ${CMAKE_CURRENT_LIST_DIR}/auth_probe.cpp)
target_link_libraries(auth_probe PRIVATE hystloop::lcm CLI11::CLI11 hystloop::warnings)
target_include_directories(auth_probe PRIVATE ${CMAKE_CURRENT_LIST_DIR}/..)

if(TARGET hystloop-bridge AND TARGET hystloop-compensator AND TARGET hystloop-ctl AND TARGET hystloop-logger
   AND TARGET hystloop-report)
  add_test(NAME auth_rig
    COMMAND ${_netns_run} -- ${CMAKE_CURRENT_LIST_DIR}/auth_rig.sh
            $<TARGET_FILE:hystloop-bridge> $<TARGET_FILE:hystloop-compensator> $<TARGET_FILE:loop_probe>
            $<TARGET_FILE:auth_probe> $<TARGET_FILE:hystloop-ctl> $<TARGET_FILE:hystloop-logger>
            $<TARGET_FILE:hystloop-report>)
  set_tests_properties(auth_rig PROPERTIES LABELS integration TIMEOUT 90 RESOURCE_LOCK hystloop_live_loop)
endif()
