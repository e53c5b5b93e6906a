# tools/spy under Xvfb against a live stream: the hystloop types load and the window comes up;
# tools/logplayer-gui under Xvfb plays a log that a subscriber receives whole.
if(HYSTLOOP_BUILD_JAVA AND TARGET hystloop_lcmtypes_jar)
  find_program(XVFB_EXECUTABLE Xvfb)
  find_program(IMPORT_EXECUTABLE import)
  if(XVFB_EXECUTABLE AND IMPORT_EXECUTABLE)
    get_target_property(_spy_jar hystloop_lcmtypes_jar JAR_FILE)
    add_test(NAME tools_spy_screenshot
      COMMAND ${_netns_run} -- ${CMAKE_CURRENT_SOURCE_DIR}/spy_screenshot.sh
              $<TARGET_FILE:lcm_probe> ${_spy_jar} ${CMAKE_CURRENT_BINARY_DIR}/spy_screenshot.png)
    set_tests_properties(tools_spy_screenshot PROPERTIES LABELS integration TIMEOUT 60)
    # tools/logplayer-gui plays a log into a subscriber from its window.
    add_test(NAME tools_logplayer_gui
      COMMAND ${_netns_run} -- ${CMAKE_CURRENT_SOURCE_DIR}/logplayer_gui.sh
              $<TARGET_FILE:lcm_probe> ${_spy_jar} ${CMAKE_CURRENT_BINARY_DIR}/logplayer_gui)
    set_tests_properties(tools_logplayer_gui PROPERTIES LABELS integration TIMEOUT 90)
  else()
    message(WARNING "Xvfb or ImageMagick's import missing: the lcm-spy screenshot test is not built")
  endif()
endif()
