#!/usr/bin/env bash
# Malformed (truncated), wrong-type, non-finite and out-of-range messages on every input channel
# of each service -- HX_COMMAND and HX_CONTROL for the bridge; HX_SENSOR, HX_TRAJECTORY, HX_PARAMS
# and HX_CONTROL for the compensator -- and blocks of two axes for these one-axis services are
# rejected and counted in HX_STATUS, and nothing unsafe reaches the actuator. Inside tools/netns-run.
#   loop_reject.sh <hystloop-bridge> <hystloop-compensator> <loop_probe>
source "$(dirname "$0")/loop_common.sh" "$@"
n=5
start_recording
"$compensator" "${compensator_args[@]}" >"$dir/compensator.log" 2>&1 & cpid=$!; pids+=($cpid)
"$bridge" "${bridge_args[@]}" --auto-arm >"$dir/bridge.log" 2>&1 & bpid=$!; pids+=($bpid)
wait_log "$dir/compensator.log" "channels:"
wait_log "$dir/bridge.log" "started in the safe state"
wait_until 20 "the bridge reported itself armed (--auto-arm)" status_at_least bridge armed 1
"$probe" control --command reset_counters    # counts from here on
wait_log "$dir/bridge.log" "RESET_COUNTERS (request"
wait_log "$dir/compensator.log" "RESET_COUNTERS (request"
"$probe" inject --target bridge --count $n
"$probe" inject --target compensator --count $n
"$probe" params --version 7 --c1 5e-9 --c2 1e-12 --c3 1.2 --valid 0   # a diagnostic set: never used
"$probe" control --command set_mode --target compensator --mode 5     # experiment is not a mode
# Reports that count every bad message (the exact counts are checked below, on the last report).
counted() {
  local reason keys=() ckeys=()
  for reason in decode_failed wrong_type non_finite out_of_range; do
    keys+=(command.rejected_$reason $n control.rejected_$reason $((2 * n)))
    ckeys+=(sensor.rejected_$reason $n trajectory.rejected_$reason $n params.rejected_$reason $n
            control.rejected_$reason $((2 * n)))
  done
  status_at_least bridge "${keys[@]}" command_blocks_wrong_axes $n &&
    status_at_least compensator "${ckeys[@]}" params_invalid 1 control_refused 1 sensor_blocks_wrong_axes $n
}
wait_until 20 "both services reported every bad message" counted
kill -TERM $bpid $cpid
wait $bpid || fail "the bridge exited with $?"
wait $cpid || fail "the compensator exited with $?"
stop_and_analyze "unsafe samples"

# Both injections send their bad HX_CONTROL messages to everyone: 2n of each there.
for reason in decode_failed wrong_type non_finite out_of_range; do
  expect_value bridge command.rejected_$reason $n
  expect_value bridge control.rejected_$reason $((2 * n))
  for endpoint in sensor trajectory params; do
    expect_value compensator $endpoint.rejected_$reason $n
  done
  expect_value compensator control.rejected_$reason $((2 * n))
done
expect_value compensator params_invalid 1
expect_value bridge command_blocks_wrong_axes $n
expect_value compensator sensor_blocks_wrong_axes $n
expect_value compensator params_swapped 0
expect_value compensator control_refused 1
expect_value bridge watchdog_trips 0
[ "$(value bridge rejected)" -ge $((12 * n)) ] || fail "bridge rejected = $(value bridge rejected), expected >= $((8 * n))"
[ "$(value compensator rejected)" -ge $((20 * n + 2)) ] || fail "compensator rejected = $(value compensator rejected)"
echo "bridge rejected $(value bridge rejected), compensator rejected $(value compensator rejected)"
echo "loop_reject: ok"
