#!/usr/bin/env bash
# kill -9 the compensator mid-run: the bridge reaches the safe state within watchdog_s + a few
# ticks of the last command it applied, never applies a voltage outside [u_min, u_max] or a step
# above the slew limit (checked on every recorded HX_SENSOR sample); a restarted compensator and
# a re-ARM resume tracking. Inside tools/netns-run.
#   loop_watchdog.sh <hystloop-bridge> <hystloop-compensator> <loop_probe>
source "$(dirname "$0")/loop_common.sh" "$@"
start_recording
"$compensator" "${compensator_args[@]}" >"$dir/compensator1.log" 2>&1 & c1=$!; pids+=($c1)
"$bridge" "${bridge_args[@]}" >"$dir/bridge.log" 2>&1 & bpid=$!; pids+=($bpid)
wait_log "$dir/compensator1.log" "channels:"
wait_log "$dir/bridge.log" "started in the safe state"
sleep 0.2
"$probe" control --command arm
wait_log "$dir/bridge.log" "ARM (request"
sleep 1.6
kill -KILL $c1
wait $c1 2>/dev/null || true
sleep 1.0
wait_log "$dir/bridge.log" "watchdog: no command"
"$compensator" "${compensator_args[@]}" >"$dir/compensator2.log" 2>&1 & c2=$!; pids+=($c2)
wait_log "$dir/compensator2.log" "channels:"
sleep 0.6
"$probe" control --command arm
for _ in $(seq 100); do [ "$(grep -c 'ARM (request' "$dir/bridge.log")" -ge 2 ] && break; sleep 0.05; done
sleep 2.2
kill -TERM $bpid $c2
wait $bpid || fail "the bridge exited with $? on SIGTERM"
wait $c2 || fail "the compensator exited with $? on SIGTERM"
stop_recording
"$probe" analyze --dir "$dir" --watchdog $watchdog_s >"$dir/analysis.txt" || { cat "$dir/analysis.txt"; fail "unsafe samples or a slow trip"; }
cat "$dir/analysis.txt"
get() { sed -n "s/^$1=//p" "$dir/analysis.txt"; }
[ "$(get safe_entries)" -ge 1 ] || fail "the bridge never entered the safe state after the kill"
[ "$(get last_run_ticks)" -ge 15000 ] || fail "tracking did not resume for long after re-arm ($(get last_run_ticks) ticks)"
awk -v e="$(get tracking_rms_m)" 'BEGIN { exit !(e < 2e-7) }' || fail "tracking error $(get tracking_rms_m) m RMS after re-arm"
trips=$(grep -c "watchdog: no command" "$dir/bridge.log" || true)
[ "$trips" -ge 1 ] || fail "the bridge did not log a watchdog trip"
grep -q "re-arm via HX_CONTROL" "$dir/status.log" || fail "no SAFE status naming the watchdog"
echo "loop_watchdog: ok (trip $(get worst_trip_ticks) ticks after the last command applied, watchdog $(get watchdog_ticks) ticks;" \
     "tracking after re-arm $(get tracking_rms_m) m RMS)"
