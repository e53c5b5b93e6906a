# hystloop-ctl's requests confirmed (or refused, naming why) by the live services on HX_STATUS:
# arm, partial gains, mode, pin-model, hold and release, disarm, shutdown (ctl_acks.sh).
# loop_probe is not in the condition: loop_services.cmake, included after this file, defines it,
# and $<TARGET_FILE:loop_probe> resolves at generate time.
if(TARGET hystloop-bridge AND TARGET hystloop-compensator AND TARGET hystloop-reidentifier AND TARGET hystloop-ctl)
  add_test(NAME ctl_acks
    COMMAND ${_netns_run} -- ${CMAKE_CURRENT_LIST_DIR}/ctl_acks.sh
            $<TARGET_FILE:hystloop-bridge> $<TARGET_FILE:hystloop-compensator> $<TARGET_FILE:loop_probe>
            $<TARGET_FILE:hystloop-reidentifier> $<TARGET_FILE:hystloop-ctl>)
  set_tests_properties(ctl_acks PROPERTIES LABELS integration TIMEOUT 90 RESOURCE_LOCK hystloop_live_loop)
endif()
