# An XY stage on the live loop: a Lissajous figure decoupled and not, per-axis tracking, one safe
# state for both axes when the compensator dies (xy_live.sh).
if(TARGET hystloop-bridge AND TARGET hystloop-compensator AND TARGET hystloop-ctl AND TARGET loop_probe)
  add_test(NAME xy_live
    COMMAND ${_netns_run} -- ${CMAKE_CURRENT_LIST_DIR}/xy_live.sh
            $<TARGET_FILE:hystloop-bridge> $<TARGET_FILE:hystloop-compensator> $<TARGET_FILE:loop_probe>
            $<TARGET_FILE:hystloop-ctl>)
  set_tests_properties(xy_live PROPERTIES LABELS integration TIMEOUT 90 RESOURCE_LOCK hystloop_live_loop)
endif()
