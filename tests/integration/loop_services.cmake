# hystloop-bridge + hystloop-compensator end to end (included by tests/integration/CMakeLists.txt):
# real processes over udpm inside tools/netns-run (ttl=0). loop_probe records HX_SENSOR,
# HX_COMMAND and HX_STATUS, sends HX_CONTROL/HX_TRAJECTORY/HX_PARAMS, injects bad messages,
# and checks the recorded samples.
add_executable(loop_probe ${CMAKE_CURRENT_LIST_DIR}/loop_probe.cpp)
target_link_libraries(loop_probe PRIVATE hystloop::lcm CLI11::CLI11 hystloop::warnings)
target_include_directories(loop_probe PRIVATE ${CMAKE_CURRENT_LIST_DIR}/..)

if(TARGET hystloop-bridge AND TARGET hystloop-compensator)
  foreach(_script loop_run loop_watchdog loop_reject bridge_cli compensator_cli bridge_safe_stop keyless_network)
    add_test(NAME ${_script}
      COMMAND ${_netns_run} -- ${CMAKE_CURRENT_LIST_DIR}/${_script}.sh
              $<TARGET_FILE:hystloop-bridge> $<TARGET_FILE:hystloop-compensator> $<TARGET_FILE:loop_probe>)
    # One 10 kHz loop of real processes at a time (RESOURCE_LOCK); unit tests may run beside it:
    # what these tests check must hold on a busy machine.
    set_tests_properties(${_script} PROPERTIES LABELS integration TIMEOUT 60 RESOURCE_LOCK hystloop_live_loop)
  endforeach()
endif()

# All four services, the logger and the re-identifier killed and restarted under load.
if(TARGET hystloop-bridge AND TARGET hystloop-reidentifier AND TARGET hystloop-logger AND TARGET logger_probe)
  add_test(NAME rig_restart
    COMMAND ${_netns_run} -- ${CMAKE_CURRENT_LIST_DIR}/rig_restart.sh
            $<TARGET_FILE:hystloop-bridge> $<TARGET_FILE:hystloop-compensator> $<TARGET_FILE:loop_probe>
            $<TARGET_FILE:hystloop-reidentifier> $<TARGET_FILE:hystloop-logger> $<TARGET_FILE:logger_probe>)
  set_tests_properties(rig_restart PROPERTIES LABELS integration TIMEOUT 120 RESOURCE_LOCK hystloop_live_loop)
endif()

# One set of actuator limits per rig: a compensator or re-identifier with others is refused.
if(TARGET hystloop-bridge AND TARGET hystloop-compensator AND TARGET hystloop-reidentifier)
  add_test(NAME rig_limits
    COMMAND ${_netns_run} -- ${CMAKE_CURRENT_LIST_DIR}/rig_limits.sh
            $<TARGET_FILE:hystloop-bridge> $<TARGET_FILE:hystloop-compensator> $<TARGET_FILE:loop_probe>
            $<TARGET_FILE:hystloop-reidentifier>)
  set_tests_properties(rig_limits PROPERTIES LABELS integration TIMEOUT 90 RESOURCE_LOCK hystloop_live_loop)
endif()
