# Replay regression (tools/replay-check, tools/replay/): the golden log (tests/data/, made by
# tools/replay/make-golden) replays into a fresh compensator exactly; a deliberately altered
# copy fails, naming the altered tick. Included by CMakeLists.txt in this folder.
if(TARGET hystloop-compensator AND TARGET hystloop-logger AND TARGET hystloop-replay-compare)
  set(_golden_dir ${PROJECT_SOURCE_DIR}/tests/data)
  add_test(NAME replay_golden
    COMMAND ${PROJECT_SOURCE_DIR}/tools/replay-check --build ${PROJECT_BINARY_DIR}
            --config ${_golden_dir}/golden-loop.compensator.yaml ${_golden_dir}/golden-loop.lcmlog)
  add_test(NAME replay_altered
    COMMAND ${_netns_run} -- ${CMAKE_CURRENT_SOURCE_DIR}/replay_altered.sh ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR})
  # A compensator at its real-time priority, fed in real time: never beside another live loop,
  # whose timing contract is judged against CPU hogs, not against a second real-time process.
  set_tests_properties(replay_golden replay_altered PROPERTIES LABELS integration TIMEOUT 90
                       RESOURCE_LOCK hystloop_live_loop)
endif()
