#!/usr/bin/env bash
# Bridge + compensator for 3 s: samples flow at 10 kHz, commands are applied, the bridge reports
# HEALTHY with its latency figures; both stop on a SHUTDOWN request. Inside tools/netns-run.
#   loop_run.sh <hystloop-bridge> <hystloop-compensator> <loop_probe>
source "$(dirname "$0")/loop_common.sh" "$@"
start_recording
"$compensator" "${compensator_args[@]}" >"$dir/compensator.log" 2>&1 & cpid=$!; pids+=($cpid)
"$bridge" "${bridge_args[@]}" --auto-arm >"$dir/bridge.log" 2>&1 & bpid=$!; pids+=($bpid)
wait_log "$dir/compensator.log" "channels:"
wait_log "$dir/bridge.log" "started in the safe state"
sleep 3.6
"$probe" control --command shutdown
for p in $bpid $cpid; do
  for _ in $(seq 50); do kill -0 $p 2>/dev/null || break; sleep 0.1; done
  kill -0 $p 2>/dev/null && fail "pid $p did not stop on SHUTDOWN"
  wait $p || fail "pid $p exited with $?"
done
stop_recording
"$probe" analyze --dir "$dir" --watchdog $watchdog_s >"$dir/analysis.txt" || { cat "$dir/analysis.txt"; fail "unsafe samples"; }
cat "$dir/analysis.txt"
get() { sed -n "s/^$1=//p" "$dir/analysis.txt"; }
[ "$(get samples)" -ge 30000 ] || fail "only $(get samples) samples in ~3.5 s at 10 kHz"
[ "$(get applied)" -ge 25000 ] || fail "only $(get applied) commands applied"
grep -q "state=4" "$dir/status.log" || fail "no STOPPING report"
# HEALTHY while it ran (a report may say DEGRADED when the shared machine stalled the loop for
# tens of milliseconds; that is what DEGRADED is for), never SAFE once armed, no watchdog trip.
grep '^process=bridge ' "$dir/status.log" | grep -q ' state=1 ' || fail "the bridge never reported HEALTHY"
grep '^process=compensator ' "$dir/status.log" | grep -q ' state=1 ' || fail "the compensator never reported HEALTHY"
grep '^process=bridge ' "$dir/status.log" | grep -q ' state=3 ' && fail "the bridge reported SAFE while armed"
expect_value bridge watchdog_trips 0
late=$(value bridge late); ticks=$(value bridge ticks)
[ $((late * 4)) -le "$ticks" ] || fail "late fraction $late / $ticks above 25 %"
echo "bridge: $(grep '^process=bridge' "$dir/status.log" | grep -v ' state=4 ' | tail -n 1 | cut -d' ' -f1-15)"
echo "bridge late fraction this period: $(value bridge late_ppm_period) ppm; cpu user $(value bridge cpu_user_us) us"
echo "compensator: $(grep '^process=compensator' "$dir/status.log" | grep -v ' state=4 ' | tail -n 1 | cut -d' ' -f1-11)"
grep summary "$dir/bridge.log" "$dir/compensator.log" | sed 's/^.*summary/summary/'
echo "loop_run: ok"
