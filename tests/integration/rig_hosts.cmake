# The rig over three hosts (network namespaces on a Linux bridge, ttl=1) through deploy/hystloop
# up --host: the demo's scenario, then the compensator moved between hosts while the loop runs.
# Inside tools/netns-run: the bridge and the namespaces live in its private namespace.
if(TARGET hystloop-bridge AND TARGET hystloop-report AND TARGET hystloop-ctl AND TARGET loop_probe)
  add_test(NAME rig_hosts
    COMMAND ${_netns_run} -- ${CMAKE_CURRENT_LIST_DIR}/rig_hosts.sh ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR}
            $<TARGET_FILE:loop_probe> ${CMAKE_CURRENT_BINARY_DIR}/rig_hosts)
  set_tests_properties(rig_hosts PROPERTIES LABELS integration TIMEOUT 900 RESOURCE_LOCK hystloop_live_loop)
endif()
