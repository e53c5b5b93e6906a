# The live loop with the re-identifier's automatic model choice on: a model change is
# published on HX_MODEL and adopted by the compensator, nothing refused (model_choice.sh).
if(TARGET hystloop-bridge AND TARGET hystloop-compensator AND TARGET hystloop-reidentifier AND TARGET hystloop-ctl
   AND TARGET loop_probe)
  add_test(NAME model_choice
    COMMAND ${_netns_run} -- ${CMAKE_CURRENT_LIST_DIR}/model_choice.sh
            $<TARGET_FILE:hystloop-bridge> $<TARGET_FILE:hystloop-compensator> $<TARGET_FILE:loop_probe>
            $<TARGET_FILE:hystloop-reidentifier> $<TARGET_FILE:hystloop-ctl>)
  set_tests_properties(model_choice PROPERTIES LABELS integration TIMEOUT 90 RESOURCE_LOCK hystloop_live_loop)
endif()
