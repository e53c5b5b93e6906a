#!/usr/bin/env bash
# The compensator plans ahead, so (1) stopping it (SIGSTOP) for less than its horizon costs no
# late tick, nor does stopping the bridge itself for 0.3 s (its simulated clock catches up gradually); (2) killing it (SIGKILL) puts the bridge in the safe state within horizon +
# watchdog_s: every plan reaches at most the horizon ahead of the last sample, and the trip
# follows the last planned tick by at most watchdog_s + a few ticks; no applied voltage ever
# leaves the actuator's range or slew limit (checked on every recorded sample); (3) a restarted
# compensator and a re-ARM resume tracking. Inside tools/netns-run.
#   loop_watchdog.sh <hystloop-bridge> <hystloop-compensator> <loop_probe>
source "$(dirname "$0")/loop_common.sh" "$@"
# A horizon of 0.2 s and a stop of 0.05 s: a wide margin whatever else the machine runs.
horizon_s=0.2
horizon_ticks=2000
stop_s=0.05
start_recording
"$compensator" "${compensator_args[@]}" --set compensator.horizon_s=$horizon_s >"$dir/compensator1.log" 2>&1 & c1=$!; pids+=($c1)
"$bridge" "${bridge_args[@]}" --set bridge.max_lead_s=0.25 >"$dir/bridge.log" 2>&1 & bpid=$!; pids+=($bpid)
wait_log "$dir/compensator1.log" "channels:"
wait_log "$dir/bridge.log" "started in the safe state"
# Commands flow before the ARM.
wait_until 20 "the compensator published commands" commands_recorded 0
"$probe" control --command arm
wait_log "$dir/bridge.log" "ARM (request"
wait_until 20 "the bridge reported itself armed" status_at_least bridge armed 1
"$probe" control --command reset_counters
wait_log "$dir/bridge.log" "RESET_COUNTERS (request"
kill -STOP $c1
sleep $stop_s   # a duration: the stall under test
kill -CONT $c1
sleep 0.5       # a duration: the two stalls apart (the buffer refilled), not one longer stall
# The bridge itself stalled (a VM's vCPU taken away): its simulated clock catches up at most
# twice as fast while the compensator refills the buffer, so that costs nothing either.
kill -STOP $bpid
sleep 0.3       # a duration: the stall under test
kill -CONT $bpid
# A report composed after the catch-up (0.15 s at most, at twice the speed).
wait_reports bridge 2 "a bridge report after the stalls"
late_after_stop=$(value bridge late)
trips_after_stop=$(value bridge watchdog_trips)
kill -KILL $c1
wait $c1 2>/dev/null || true
wait_log "$dir/bridge.log" "watchdog: no command"
recorded=$(stat -c %s "$dir/command.csv")   # no commands from here until the new compensator's
"$compensator" "${compensator_args[@]}" >"$dir/compensator2.log" 2>&1 & c2=$!; pids+=($c2)
wait_log "$dir/compensator2.log" "channels:"
wait_until 20 "the restarted compensator published commands" commands_recorded "$recorded"
"$probe" control --command arm
# Tracking after the trip must come from this ARM (the bridge waits for one after a watchdog trip).
second_arm() { [ "$(grep -c 'ARM (request' "$dir/bridge.log")" -ge 2 ]; }
wait_until 10 "the bridge took the second ARM" second_arm
sleep 2.2   # a duration: tracking after the re-arm (the analysis wants >= 15000 ticks of it)
kill -TERM $bpid $c2
wait $bpid || fail "the bridge exited with $? on SIGTERM"
wait $c2 || fail "the compensator exited with $? on SIGTERM"
stop_and_analyze "unsafe samples or a slow trip"
[ "$late_after_stop" -eq 0 ] || fail "a ${stop_s} s stop of the compensator or a 0.3 s stop of the bridge cost $late_after_stop late ticks (horizon $horizon_s s)"
[ "$trips_after_stop" -eq 0 ] || fail "the watchdog tripped during a stop shorter than the horizon"
[ "$(get safe_entries)" -ge 1 ] || fail "the bridge never entered the safe state after the kill"
expect_within_horizon
[ "$(get last_run_ticks)" -ge 15000 ] || fail "tracking did not resume for long after re-arm ($(get last_run_ticks) ticks)"
# Measured 2.5-2.6 nm RMS after re-arm (3 runs, 2-core machine shared with builds); 10 nm is ~4x
# that: room for a loaded host; the earlier 200 nm let a loop 80x worse than this one pass.
awk -v e="$(get tracking_rms_m)" 'BEGIN { exit !(e < 1e-8) }' || fail "tracking error $(get tracking_rms_m) m RMS after re-arm"
trips=$(grep -c "watchdog: no command" "$dir/bridge.log" || true)
[ "$trips" -ge 1 ] || fail "the bridge did not log a watchdog trip"
grep -q "re-arm via HX_CONTROL" "$dir/status.log" || fail "no SAFE status naming the watchdog"
echo "loop_watchdog: ok (stopped ${stop_s} s: 0 late ticks; killed: trip $(get worst_trip_ticks) ticks after the last" \
     "planned tick (watchdog $(get watchdog_ticks) ticks), plans at most $(get max_planned_ahead_ticks) ticks ahead;" \
     "tracking after re-arm $(get tracking_rms_m) m RMS)"
