#!/usr/bin/env bash
# The rig keeps the stage safe and loses nothing silently while its helpers die: all four services
# beside two CPU-bound processes (stress-ng --cpu 2), tracking from wrong MEM parameters; forged
# traffic arrives (a parameter set with version 2147483647, sensor blocks far behind the clock),
# then the logger and the re-identifier are killed (SIGKILL) and restarted. Asserts: no applied
# voltage out of range or slew, no watchdog trip, no late tick, no restart of the control law; the
# killed logger's file and the new one read to their ends; the restarted re-identifier (a new
# publisher) gets a parameter set adopted despite the forged version. Inside tools/netns-run.
#   rig_restart.sh <bridge> <compensator> <loop_probe> <reidentifier> <logger> <logger_probe>
source "$(dirname "$0")/loop_common.sh" "$@"
reident="$4" logger="$5" lprobe="$6"
demo="$config/demo"
start_recording
stress-ng --cpu 2 --timeout 60s >/dev/null 2>&1 & pids+=($!)
start_logger() { "$logger" --out-dir "$dir/logs" >"$dir/logger$1.log" 2>&1 & lpid=$!; pids+=($lpid); }
start_reident() { "$reident" --config "$demo/reidentifier.yaml" >"$dir/reident$1.log" 2>&1 & rpid=$!; pids+=($rpid); }
mkdir -p "$dir/logs"
start_logger 1
"$compensator" --config "$demo/compensator.yaml" >"$dir/compensator.log" 2>&1 & cpid=$!; pids+=($cpid)
"$bridge" --config "$demo/bridge.yaml" >"$dir/bridge.log" 2>&1 & bpid=$!; pids+=($bpid)
start_reident 1
wait_log "$dir/compensator.log" "channels:"
wait_log "$dir/bridge.log" "started in the safe state"
wait_until 20 "the compensator published commands (before the ARM)" commands_recorded 0
"$probe" control --command arm
wait_log "$dir/bridge.log" "ARM (request"
"$probe" trajectory --version 1 --shape 2 --amplitude-m -1.6e-6 --frequency-hz 1 --blend-s 0.5
wait_log "$dir/compensator.log" "trajectory v1"
sleep 3   # a duration: the rig tracks under load before the forged traffic
# Forged traffic from outside the rig: a parameter set with the highest version there is, and
# sensor blocks far behind the bridge's clock (loop_probe inject: seq 1, plus malformed ones).
"$probe" params --version 2147483647 --c1 5e-9 --c2 1e-12 --c3 1.2
"$probe" inject --target compensator --count 3
wait_until 20 "the compensator reported the forged messages" status_at_least compensator \
  sensor.rejected_out_of_range 3 trajectory.rejected_out_of_range 3 params.rejected_out_of_range 3 \
  control.rejected_out_of_range 3 params.received 1
kill -KILL $lpid; wait $lpid 2>/dev/null || true
sleep 0.5   # a duration: the rig runs without a logger
start_logger 2
wait_log "$dir/logger2.log" "recording '"
# The new logger's file has events in it (flushed every 0.2 s).
second_log_written() { [ "$(find "$dir/logs" -name '*.lcmlog' -size +0 | wc -l)" -ge 2 ]; }
wait_until 20 "the restarted logger wrote its file" second_log_written
accepted_before=$(value compensator params_accepted)
kill -KILL $rpid; wait $rpid 2>/dev/null || true
sleep 0.5   # a duration: the rig runs without a re-identifier
start_reident 2
# The restarted re-identifier needs a window of branches (4 s) to refit.
wait_until 30 "the compensator accepted a set from the restarted re-identifier" \
  status_at_least compensator params_accepted $((accepted_before + 1))
wait_reports bridge 2 "a bridge report with the new set in use"
trips=$(value bridge watchdog_trips)
accepted_after=$(value compensator params_accepted)
"$probe" control --command disarm
wait_log "$dir/bridge.log" "DISARM (request"
kill -TERM $bpid $cpid $rpid $lpid
wait $bpid || fail "the bridge exited with $?"
wait $cpid || fail "the compensator exited with $?"
stop_and_analyze "unsafe samples"
[ "$trips" -eq 0 ] || fail "$trips watchdog trips while the logger and the re-identifier were restarted"
restarts=$(value compensator bridge_restarts)
[ "$restarts" -eq 0 ] || fail "forged sensor blocks restarted the compensator's control law ($restarts)"
[ "$(value bridge late)" -eq 0 ] || fail "$(value bridge late) late ticks: forged blocks or restarts disturbed the plan"
[ "$accepted_after" -gt "$accepted_before" ] || fail "no parameter set accepted from the restarted re-identifier ($accepted_before -> $accepted_after)"
grep -q "accepted" "$dir/compensator.log" || fail "the compensator logged no accepted set"
files=$(ls "$dir/logs"/*.lcmlog | wc -l)
[ "$files" -ge 2 ] || fail "expected the killed logger's file and the new one, found $files"
"$lprobe" read-logs "$dir/logs"/*.lcmlog >"$dir/read.json" || { cat "$dir/read.json"; fail "a log file does not read to its end"; }
echo "rig_restart: ok (0 watchdog trips, params accepted $accepted_before -> $accepted_after, logs: $(cat "$dir/read.json"))"
