#!/usr/bin/env bash
# One set of actuator limits per rig, the bridge's: a compensator or a re-identifier started with
# other limits, or a nominal gain more than its plausible_gain_factor off the bridge's, is refused
# at the bridge's first report (exit 2, naming the key, both values and where each came from);
# started with the bridge's, each runs on. Inside tools/netns-run.
#   rig_limits.sh <hystloop-bridge> <hystloop-compensator> <loop_probe> <hystloop-reidentifier>
source "$(dirname "$0")/loop_common.sh" "$@"
reidentifier="$4"
"$bridge" "${bridge_args[@]}" >"$dir/bridge.log" 2>&1 & bpid=$!; pids+=($bpid)
wait_log "$dir/bridge.log" "started in the safe state"

# Refused: exit 2 within a few bridge reports (1 Hz), the error naming both values.
expect_rig_refusal() {  # log-name expected-text... -- command...
  local log="$dir/$1.log"; shift
  local texts=()
  while [ "$1" != "--" ]; do texts+=("$1"); shift; done
  shift
  local rc=0
  timeout 30 "$@" >"$log" 2>&1 || rc=$?
  [ "$rc" -eq 2 ] || fail "$* exited $rc, not 2 (refused)"
  for t in "${texts[@]}"; do grep -qF -- "$t" "$log" || fail "no '$t' in $log"; done
}
expect_rig_refusal compensator_range \
  "actuator.u_max_V: 200 in this compensator's configuration (--set), 250 at the bridge on" "axis x" -- \
  "$compensator" --config "$config/compensator.yaml" --set actuator.u_max_V=200
expect_rig_refusal compensator_slew \
  "actuator.slew_V_per_s: 10000 in this compensator's configuration (--set), 50000 at the bridge" -- \
  "$compensator" --config "$config/compensator.yaml" --set actuator.slew_V_per_s=1e4
expect_rig_refusal reidentifier_range \
  "actuator.u_min_V: -200 in this reidentifier's configuration (--set), -250 at the bridge" -- \
  "$reidentifier" --config "$config/reidentifier.yaml" --set actuator.u_min_V=-200

# The bridge's own limits: both run on past several reports and stop cleanly.
"$compensator" --config "$config/compensator.yaml" --seconds 3 >"$dir/compensator_same.log" 2>&1 \
  || fail "a compensator with the bridge's limits exited $?"
"$reidentifier" --config "$config/reidentifier.yaml" >"$dir/reidentifier_same.log" 2>&1 & rpid=$!; pids+=($rpid)
sleep 3  # a duration: several of the bridge's reports
kill -TERM $rpid
wait $rpid || fail "a re-identifier with the bridge's limits exited $?"
grep -q "error refused:" "$dir/compensator_same.log" "$dir/reidentifier_same.log" && fail "refused with the bridge's limits"
kill -TERM $bpid
wait $bpid || fail "the bridge exited with $? on SIGTERM"

# A bridge whose stage is a hundred times steeper than the compensator's linear.gain (a 100 um
# stage left with the simulator's gain): more than plausible_gain_factor apart, refused.
"$bridge" "${bridge_args[@]}" --set servo.nominal_gain_m_per_V=6.3e-7 >"$dir/bridge2.log" 2>&1 & bpid=$!; pids+=($bpid)
wait_log "$dir/bridge2.log" "started in the safe state"
expect_rig_refusal compensator_gain \
  "linear.gain: 6.34e-09 m/V in this compensator's configuration" "6.3e-07 m/V at the bridge on" \
  "more than x10 (compensator.plausible_gain_factor) apart" -- \
  "$compensator" --config "$config/compensator.yaml"
kill -TERM $bpid
wait $bpid || fail "the second bridge exited with $? on SIGTERM"
echo "ok: other limits and a gain of another stage refused naming both, the bridge's accepted"
