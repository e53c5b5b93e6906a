#!/usr/bin/env bash
# Bridge + compensator for ~3.5 s with the product's defaults: samples flow at 10 kHz in blocks,
# commands planned ahead are applied, the bridge reports HEALTHY, never trips its 2 ms watchdog;
# both stop on a SHUTDOWN request. Inside tools/netns-run.
#   loop_run.sh <hystloop-bridge> <hystloop-compensator> <loop_probe>
source "$(dirname "$0")/loop_common.sh" "$@"
start_recording
"$compensator" "${compensator_args[@]}" >"$dir/compensator.log" 2>&1 & cpid=$!; pids+=($cpid)
"$bridge" "${bridge_args[@]}" --auto-arm >"$dir/bridge.log" 2>&1 & bpid=$!; pids+=($bpid)
wait_log "$dir/compensator.log" "channels:"
wait_log "$dir/bridge.log" "started in the safe state"
# The run lasts until the recorder holds 35000 samples (3.5 s of the loop's ticks: what the checks
# below need), however long a loaded machine takes to get there.
wait_until 40 "the recorder held 35000 samples" samples_recorded 35000
"$probe" control --command shutdown
expect_shutdown 50 $bpid $cpid
stop_and_analyze "unsafe samples"
[ "$(get samples)" -ge 30000 ] || fail "only $(get samples) samples in ~3.5 s at 10 kHz"
[ "$(get seq_gaps)" -eq 0 ] || fail "$(get seq_gaps) gaps in the sample ticks"
[ "$(get applied)" -ge 25000 ] || fail "only $(get applied) commands applied"
expect_within_horizon
grep -q "state=4" "$dir/status.log" || fail "no STOPPING report"
# HEALTHY while it ran (a report may say DEGRADED when the shared machine stalled the loop for
# tens of milliseconds; that is what DEGRADED is for), never SAFE once armed, no watchdog trip.
grep -q '^process=bridge \(.* \)\?state=1 ' "$dir/status.log" || fail "the bridge never reported HEALTHY"
grep -q '^process=compensator \(.* \)\?state=1 ' "$dir/status.log" || fail "the compensator never reported HEALTHY"
grep -q '^process=bridge \(.* \)\?state=3 ' "$dir/status.log" && fail "the bridge reported SAFE while armed"
expect_value bridge watchdog_trips 0
late=$(value bridge late); ticks=$(value bridge ticks)
[ $((late * 100)) -le "$ticks" ] || fail "late fraction $late / $ticks above 1 %: the horizon did not cover the stalls"
echo "bridge: $(grep '^process=bridge' "$dir/status.log" | grep -v ' state=4 ' | tail -n 1 | cut -d' ' -f1-15)"
echo "bridge late fraction this period: $(value bridge late_ppm_period) ppm; cpu user $(value bridge cpu_user_us) us"
echo "compensator: $(grep '^process=compensator' "$dir/status.log" | grep -v ' state=4 ' | tail -n 1 | cut -d' ' -f1-11)"
grep summary "$dir/bridge.log" "$dir/compensator.log" | sed 's/^.*summary/summary/'
echo "loop_run: ok"
