# The live loop with the re-identifier, driven by hystloop-ctl:
#  ctl_acks.sh: hystloop-ctl's requests confirmed (or refused, naming why) by the live services on
#    HX_STATUS: arm, partial gains, mode, pin-model, hold and release, disarm, shutdown;
#  model_choice.sh: the re-identifier's automatic model choice on: a model change is published on
#    HX_MODEL and adopted by the compensator, nothing refused.
# loop_probe is not in the condition: loop_services.cmake, included after this file, defines it,
# and $<TARGET_FILE:loop_probe> resolves at generate time.
if(TARGET hystloop-bridge AND TARGET hystloop-compensator AND TARGET hystloop-reidentifier AND TARGET hystloop-ctl)
  foreach(_script ctl_acks model_choice)
    add_test(NAME ${_script}
      COMMAND ${_netns_run} -- ${CMAKE_CURRENT_LIST_DIR}/${_script}.sh
              $<TARGET_FILE:hystloop-bridge> $<TARGET_FILE:hystloop-compensator> $<TARGET_FILE:loop_probe>
              $<TARGET_FILE:hystloop-reidentifier> $<TARGET_FILE:hystloop-ctl>)
    set_tests_properties(${_script} PROPERTIES LABELS integration TIMEOUT 90 RESOURCE_LOCK hystloop_live_loop)
  endforeach()
endif()
