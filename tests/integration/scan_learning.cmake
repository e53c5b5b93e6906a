# A raster line with learning on the live loop (deploy/hystloop scan, shortened): a 50 Hz 1 um
# triangle taken, no late or clamped tick, learning_periods growing, the last second's RMS bounded
# (scan_learning.sh).
if(TARGET hystloop-bridge AND TARGET hystloop-compensator AND TARGET hystloop-ctl AND TARGET loop_probe)
  add_test(NAME scan_learning
    COMMAND ${_netns_run} -- ${CMAKE_CURRENT_LIST_DIR}/scan_learning.sh
            $<TARGET_FILE:hystloop-bridge> $<TARGET_FILE:hystloop-compensator> $<TARGET_FILE:loop_probe>
            $<TARGET_FILE:hystloop-ctl>)
  set_tests_properties(scan_learning PROPERTIES LABELS integration TIMEOUT 90 RESOURCE_LOCK hystloop_live_loop)
endif()
