# Every program's exit codes on its command line (core/cli.hpp): --help 0, a bad option 2.
set(_exit_code_programs)
foreach(_program hystloop-bridge hystloop-compensator hystloop-logger hystloop-reidentifier hystloop-identify
                 hystloop-model hystloop-report hystloop-ctl hystloop-timer-check hystloop-replay-filter
                 hystloop-replay-compare hystloop-lcm-fanout hystloop-export)
  if(TARGET ${_program})
    list(APPEND _exit_code_programs $<TARGET_FILE:${_program}>)
  endif()
endforeach()
add_test(NAME exit_codes COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/exit_codes.sh ${_exit_code_programs})
set_tests_properties(exit_codes PROPERTIES LABELS unit TIMEOUT 60)
