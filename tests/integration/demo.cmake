# All four services together, through the deploy script, as the README's main command runs them.
# RUN_SERIAL: a 10 kHz loop of four processes wants the machine's two cores to itself.
if(TARGET hystloop-bridge AND TARGET hystloop-report AND TARGET hystloop-ctl)
  add_test(NAME loop_demo_all_services
    COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/demo_check.sh ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR}
            ${CMAKE_CURRENT_BINARY_DIR}/demo)
  set_tests_properties(loop_demo_all_services PROPERTIES LABELS integration TIMEOUT 180 RUN_SERIAL TRUE)
endif()

# Banning's sine series on the live loop, through the deploy script, and the fit of its log.
if(TARGET hystloop-bridge AND TARGET hystloop-identify AND TARGET hystloop-ctl)
  add_test(NAME loop_banning_series
    COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/banning_check.sh ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR}
            ${CMAKE_CURRENT_BINARY_DIR}/banning)
  set_tests_properties(loop_banning_series PROPERTIES LABELS integration TIMEOUT 180 RUN_SERIAL TRUE)
endif()
