#!/usr/bin/env bash
# A keyless rig that finds itself on a network: the bridge (armed, tracking) and the compensator
# start keyless inside this private namespace, where the start check lets them; then an interface
# other than loopback comes up (a veth pair made inside the namespace: it reaches nothing, but the
# services cannot know that). Both must stop within a few seconds, saying why, the bridge through
# its safe ramp. Inside tools/netns-run --keyless.
#   keyless_network.sh <hystloop-bridge> <hystloop-compensator> <loop_probe>
source "$(dirname "$0")/loop_common.sh" "$@"
command -v ip >/dev/null || fail "ip (iproute2) is needed"

"$compensator" "${compensator_args[@]}" >"$dir/compensator.log" 2>&1 & cpid=$!; pids+=($cpid)
"$bridge" "${bridge_args[@]}" --auto-arm >"$dir/bridge.log" 2>&1 & bpid=$!; pids+=($bpid)
wait_log "$dir/compensator.log" "channels:"
wait_log "$dir/bridge.log" "started in the safe state"
sleep 1.5
kill -0 $bpid && kill -0 $cpid || fail "a service stopped before any interface came up"

ip link add hxkl0 type veth peer name hxkl1
ip link set hxkl0 up
ip link set hxkl1 up
for p in $bpid $cpid; do
  for _ in $(seq 100); do kill -0 "$p" 2>/dev/null || break; sleep 0.05; done
  kill -0 "$p" 2>/dev/null && fail "a keyless service still runs 5 s after an interface came up"
done
wait $bpid || true
wait $cpid || true
for log in bridge compensator; do
  grep -q "interfaces .*hxkl.* came up after the start" "$dir/$log.log" || fail "the $log did not say why it stopped"
done
grep -q "stopping: ramping to the safe" "$dir/bridge.log" || fail "the bridge did not stop through its safe ramp"
echo "keyless_network: both services stopped, naming the interfaces; the bridge ramped to safe"
