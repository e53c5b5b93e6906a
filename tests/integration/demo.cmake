# Runs of the deploy script (deploy/hystloop) on the live loop, each checked by its script:
# <script> <source dir> <build dir> <output dir>. RUN_SERIAL: a 10 kHz loop of four processes
# wants the machine's two cores to itself.
function(hystloop_deploy_test NAME SCRIPT OUT)
  add_test(NAME ${NAME}
    COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/${SCRIPT} ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR}
            ${CMAKE_CURRENT_BINARY_DIR}/${OUT})
  set_tests_properties(${NAME} PROPERTIES LABELS integration TIMEOUT 180 RUN_SERIAL TRUE)
endfunction()

# All four services together, as the README's main command runs them.
if(TARGET hystloop-bridge AND TARGET hystloop-report AND TARGET hystloop-ctl)
  hystloop_deploy_test(loop_demo_all_services demo_check.sh demo)
endif()

# Banning's sine series on the live loop, and the fit of its log.
if(TARGET hystloop-bridge AND TARGET hystloop-identify AND TARGET hystloop-ctl)
  hystloop_deploy_test(loop_banning_series banning_check.sh banning)
endif()

# A stage's dynamics measured on the live loop (the two-mode example), and the fit of its log.
if(TARGET hystloop-bridge AND TARGET hystloop-identify AND TARGET hystloop-ctl)
  hystloop_deploy_test(loop_stage_identification stage_check.sh stage)
endif()
