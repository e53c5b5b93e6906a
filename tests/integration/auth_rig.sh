#!/usr/bin/env bash
# The authenticated rig (README "Authenticated rig"): hystloop-ctl keygen writes a 0600 key and
# will not overwrite it; a key file open to others stops the bridge at start (exit 2, "chmod 600");
# a keyed bridge + compensator then run, and a publisher without the key sends ARM, a mode,
# command blocks, a trajectory and a parameter set: nothing acts, the stage stays in the safe
# state, and every message is counted as refused on HX_STATUS. A signed command block captured
# from the running rig and replayed (at once: replayed; after the skew window: skewed) is refused.
# The sensor stream is signed too: three forged blocks 5000 ticks ahead (which the sequence guard
# would confirm as a jump) and a replayed real block are refused before the guard sees them.
# A keyed logger records none of what the services refused (no gap, no out-of-order block, no
# foreign parameter set: counted by reason instead), and hystloop-report reads its record with
# the key, and warns without it.
# Inside tools/netns-run.
#   auth_rig.sh <hystloop-bridge> <hystloop-compensator> <loop_probe> <auth_probe> <hystloop-ctl>
#               <hystloop-logger> <hystloop-report>
source "$(dirname "$0")/loop_common.sh" "$1" "$2" "$3"
authp="$4"; ctl="$5"; logger="$6"; report="$7"
key="$dir/rig.key"

"$ctl" keygen --out "$key" >/dev/null || fail "keygen failed"
[ "$(stat -c %a "$key")" = 600 ] || fail "keygen wrote mode $(stat -c %a "$key"), expected 600"
set +e; "$ctl" keygen --out "$key" 2>"$dir/keygen.err"; rc=$?; set -e
[ "$rc" = 2 ] && grep -q -- "--force" "$dir/keygen.err" || fail "keygen over an existing key: exit $rc"

chmod 644 "$key"
set +e; "$bridge" "${bridge_args[@]}" --set auth.key_file="$key" --seconds 1 >"$dir/open_key.log" 2>&1; rc=$?; set -e
[ "$rc" = 2 ] || fail "the bridge started with a key file open to others (exit $rc)"
grep -q "chmod 600 $key" "$dir/open_key.log" || fail "no 'chmod 600 $key' in: $(cat "$dir/open_key.log")"
chmod 600 "$key"

auth=(--set auth.key_file="$key")
start_recording
"$logger" "${auth[@]}" --out-dir "$dir/rec" --summary "$dir/rec.json" >"$dir/logger.log" 2>&1 & lpid=$!; pids+=($lpid)
wait_log "$dir/logger.log" "recording"
"$compensator" "${compensator_args[@]}" "${auth[@]}" >"$dir/compensator.log" 2>&1 & cpid=$!; pids+=($cpid)
"$bridge" "${bridge_args[@]}" "${auth[@]}" >"$dir/bridge.log" 2>&1 & bpid=$!; pids+=($bpid)   # not armed
wait_log "$dir/compensator.log" "channels:"
wait_log "$dir/bridge.log" "started in the safe state"
grep -q "auth: sensor blocks, commands, control" "$dir/bridge.log" || fail "the bridge did not say it checks signatures"
wait_until 20 "the compensator published commands" commands_recorded 0
"$authp" capture --channel COMMAND --out "$dir/early.bin" >/dev/null || fail "no command block to capture"
"$ctl" --key-file "$key" reset-counters >/dev/null   # signed: counts from here on
wait_log "$dir/bridge.log" "RESET_COUNTERS (request"
wait_log "$dir/compensator.log" "RESET_COUNTERS (request"

# The foreign publisher: no key. Nothing it asks for is confirmed (hystloop-ctl exits 1).
for request in "arm" "mode off" "params --c1 5e-9 --c2 1e-12 --c3 1.2 --version 9"; do
  # shellcheck disable=SC2086  # the words of the request
  if "$ctl" $request --timeout 1 >"$dir/foreign.out" 2>&1; then fail "an unsigned '$request' was confirmed"; fi
  grep -q "not confirmed\|did not adopt" "$dir/foreign.out" || fail "ctl $request: $(cat "$dir/foreign.out")"
done
"$ctl" trajectory --shape hold --offset 1e-7 --no-wait >/dev/null  # refused unsigned: no verdict to wait for
"$authp" commands --count 10 >/dev/null
# A signed block captured now and replayed at once: its counter was seen.
"$authp" capture --channel COMMAND --out "$dir/now.bin" >/dev/null
"$authp" replay --channel COMMAND --in "$dir/now.bin"
# Forged sensor blocks far ahead, and a real one captured and replayed.
"$authp" sensor-jump --ahead 5000 --count 3 >/dev/null || fail "could not send the forged sensor blocks"
"$authp" capture --channel SENSOR --out "$dir/sensor.bin" >/dev/null || fail "no sensor block to capture"
"$authp" replay --channel SENSOR --in "$dir/sensor.bin"
# The one captured before the reset, now older than auth.max_skew_s (2 s): a recording.
sleep_left=$(awk -v t="$(stat -c %Y "$dir/early.bin")" -v now="$(date +%s)" 'BEGIN { s = t + 3.2 - now; print (s > 0 ? s : 0) }')
sleep "$sleep_left"   # a duration: until the early block is older than the skew window
"$authp" replay --channel COMMAND --in "$dir/early.bin"
# Reports that count everything refused (the exact counts are checked below, on the last report).
refusals_reported() {
  status_at_least bridge command.rejected_unsigned 10 command.rejected_replayed 1 command.rejected_skewed 1 \
    control.rejected_unsigned 3 command.accepted 101 &&
  status_at_least compensator trajectory.rejected_unsigned 1 params.rejected_unsigned 1 control.rejected_unsigned 1 \
    sensor.rejected_unsigned 3 sensor.rejected_replayed 1 sensor.accepted 101
}
wait_until 20 "both services reported every refused message" refusals_reported
kill -TERM $bpid $cpid
wait $bpid || fail "the bridge exited with $?"
wait $cpid || fail "the compensator exited with $?"
kill -TERM $lpid
wait $lpid || fail "the logger exited with $?"
stop_recording

# The record holds what the rig took: what it refused is counted by the logger, not recorded.
rec() { jq -r "$1" "$dir/rec.json"; }
[ "$(rec .keyed)" = true ] || fail "the logger's summary does not say keyed"
[ "$(rec .channels.HX_COMMAND.refused.unsigned)" -ge 10 ] || fail "logger HX_COMMAND refused unsigned $(rec .channels.HX_COMMAND.refused.unsigned)"
[ "$(rec .channels.HX_SENSOR.refused.unsigned)" -ge 3 ] || fail "logger HX_SENSOR refused unsigned $(rec .channels.HX_SENSOR.refused.unsigned)"
[ "$(rec .channels.HX_SENSOR.refused.replayed)" -ge 1 ] || fail "logger HX_SENSOR refused replayed $(rec .channels.HX_SENSOR.refused.replayed)"
[ "$(rec .channels.HX_PARAMS.refused.unsigned)" -ge 1 ] || fail "logger HX_PARAMS refused unsigned $(rec .channels.HX_PARAMS.refused.unsigned)"
[ "$(rec .channels.HX_PARAMS.written)" = 0 ] || fail "the logger recorded an unsigned parameter set"
for ch in HX_SENSOR HX_COMMAND; do
  for what in missing out_of_order; do
    [ "$(rec ".channels.$ch.sequence.$what")" = 0 ] || fail "logger $ch $what $(rec ".channels.$ch.sequence.$what")"
  done
done
logs=("$dir"/rec/*.lcmlog)
"$report" "${logs[@]}" --out "$dir/report_nokey" --no-plots --quiet 2>"$dir/report_nokey.err" ||
  fail "hystloop-report without the key: $(cat "$dir/report_nokey.err")"
grep -q "recorded on a keyed rig; signatures not checked" "$dir/report_nokey.err" ||
  fail "hystloop-report did not warn that it read a keyed log unverified: $(cat "$dir/report_nokey.err")"
"$report" "${logs[@]}" --out "$dir/report_key" --no-plots --quiet --key-file "$key" 2>"$dir/report_key.err" ||
  fail "hystloop-report with the key: $(cat "$dir/report_key.err")"
[ "$(jq .signatures_verified "$dir/report_key/summary.json")" = true ] || fail "the report did not verify"
[ "$(jq .unverified_events_left_out "$dir/report_key/summary.json")" = 0 ] || fail "the keyed record held unverified events"
[ "$(jq .params_updates "$dir/report_key/summary.json")" = 0 ] || fail "the report lists a parameter set the rig refused"

expect_value bridge command.rejected_unsigned 10
expect_value bridge command.rejected_replayed 1
expect_value bridge command.rejected_skewed 1
expect_value bridge command.rejected_bad_mac 0
[ "$(value bridge command.accepted)" -gt 100 ] || fail "the bridge took few signed command blocks: $(value bridge command.accepted)"
[ "$(value bridge control.rejected_unsigned)" -ge 3 ] || fail "bridge control.rejected_unsigned = $(value bridge control.rejected_unsigned)"
expect_value bridge control_acted 0           # ARM never acted on
expect_value bridge armed 0
expect_value bridge applied 0                 # no command reached the stage: safe state throughout
for endpoint in trajectory params control; do
  [ "$(value compensator $endpoint.rejected_unsigned)" -ge 1 ] || fail "compensator $endpoint.rejected_unsigned = $(value compensator $endpoint.rejected_unsigned)"
done
expect_value compensator trajectory.accepted 0
expect_value compensator params.accepted 0
expect_value compensator control_acted 1       # the signed reset-counters only
expect_value compensator trajectories 0
[ "$(value compensator sensor.rejected_unsigned)" -ge 3 ] || fail "compensator sensor.rejected_unsigned = $(value compensator sensor.rejected_unsigned)"
[ "$(value compensator sensor.rejected_replayed)" -ge 1 ] || fail "compensator sensor.rejected_replayed = $(value compensator sensor.rejected_replayed)"
expect_value compensator sensor_jumps 0
expect_value compensator sensor_blocks_held 0   # refused before the sequence guard
[ "$(value compensator sensor.accepted)" -gt 100 ] || fail "the compensator took few signed sensor blocks: $(value compensator sensor.accepted)"
expect_value compensator params_accepted 0
echo "bridge refused: command unsigned $(value bridge command.rejected_unsigned), replayed $(value bridge command.rejected_replayed)," \
     "skewed $(value bridge command.rejected_skewed), control unsigned $(value bridge control.rejected_unsigned)"
# A restarted receiver: an ARM signed (and captured) before the bridge started, replayed within
# the skew window (2 s: only the bridge's start lies between), is refused as replayed; the bridge
# stays in the safe state.
start_recording
"$authp" capture --channel CONTROL --out "$dir/arm.bin" >"$dir/capture_arm.out" 2>&1 & cap=$!; pids+=($cap)
# No bridge runs to confirm the ARM: it is captured. Signed ARMs until the capture (subscribed at
# some point after its start) took one.
arm_captured() { kill -0 $cap 2>/dev/null || return 0; "$ctl" --key-file "$key" arm --no-wait >/dev/null; return 1; }
wait_until 10 "the capture took a signed ARM" arm_captured
wait $cap || fail "no signed ARM captured"
"$bridge" "${bridge_args[@]}" "${auth[@]}" --summary-json "$dir/bridge2.json" >"$dir/bridge2.log" 2>&1 & b2=$!; pids+=($b2)
wait_log "$dir/bridge2.log" "started in the safe state"
"$authp" replay --channel CONTROL --in "$dir/arm.bin"
wait_until 20 "the restarted bridge reported the replayed ARM" status_at_least bridge control.rejected_replayed 1
kill -TERM $b2; wait $b2 || fail "the restarted bridge exited with $?"
stop_recording
[ "$(value bridge control.rejected_replayed)" -ge 1 ] || fail "the restarted bridge did not refuse the ARM signed before it started (control.rejected_replayed $(value bridge control.rejected_replayed))"
expect_value bridge control_acted 0
[ "$(jq .armed_ticks "$dir/bridge2.json")" = 0 ] || fail "the restarted bridge armed on a replayed ARM"

echo "auth_rig: ok"
