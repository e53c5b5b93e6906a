# Sourced by rig_hosts.sh on a keyed rig, after `up` and before the scenario (the bridge is
# SAFE at 0 V, the compensator waits for a trajectory): a publisher on the desk without the key
# (hystloop-ctl without --key-file, and a keyless compensator planning commands for 2 s) sends
# ARM, START_EXPERIMENT, a trajectory, a parameter set and command blocks. Nothing changes on the
# stage (the bridge stays SAFE, every recorded u is 0 V, the compensator accepts nothing) and each
# kind is counted refused as unsigned on HX_STATUS (the desk's recording of it).
# Uses rig_hosts.sh's in_ns, ctl_exe, build, cfg, out, prefix, fail.
foreign_url="udpm://239.255.76.67:7667?ttl=1"
# The rig's services by host: the keyless compensator below reports as "compensator" too, from the
# desk, so every count is read from the reports of the real one (host and pid are in each line).
declare -A home=([bridge]=stage [compensator]=control)
last_report() { grep "^process=$1 .* host=${home[$1]} pid=" "$out/desk/status.log" | tail -n 1; }
reports() {  # process -> how many reports of it (from its host) the desk has recorded
  local n; n=$(grep -c "^process=$1 .* host=${home[$1]} pid=" "$out/desk/status.log" 2>/dev/null) || true
  echo "${n:-0}"
}
counter() {  # process, counter name -> its value in the last report (the last of duplicate names)
  last_report "$1" | tr ' ' '\n' | awk -F= -v k="$2" '$1 == k { v = $2 } END { print v + 0 }'
}
foreign_counts() {
  local p k
  for p in bridge compensator; do
    for k in control.rejected_unsigned command.rejected_unsigned trajectory.rejected_unsigned \
      params.rejected_unsigned control.accepted trajectory.accepted params.accepted params_accepted; do
      echo "$p.$k=$(counter "$p" "$k")"
    done
  done
}
# The counts before: a report of each (`status` heard them already; the desk's recorder too).
heard_both() { [ "$(reports bridge)" -gt 0 ] && [ "$(reports compensator)" -gt 0 ]; }
wait_until 20 "the desk recorded a report of the bridge and of the compensator" heard_both
foreign_counts >"$out/foreign-before.txt"
# The recorder is still writing sensor.csv: its last line may be incomplete, so every read below
# drops it (a half-written row once read as "u moved" and a truncated seq as the start).
complete_rows() { head -n -1 "$out/desk/sensor.csv"; }
seq_before=$(complete_rows | tail -n 1 | cut -d, -f1)
foreign() { in_ns desk "$ctl_exe" --lcm-url "$foreign_url" --allow-network --rig "$prefix" "$@" >/dev/null; }
if foreign arm --timeout 1 2>/dev/null; then echo "FAIL: a keyless ARM from the desk was confirmed"; fail=1
else echo "ok:   a keyless ARM from the desk is not confirmed (hystloop-ctl exit 1)"; fi
foreign experiment --mem-paper --duration 2 --no-wait  # refused unsigned: nobody answers
foreign trajectory --mem-paper --blend 0.5 --no-wait
foreign params --c1 2e-9 --c2 2e-9 --c3 0.3 --version 1000 --no-wait
# A keyless service on a host's network is refused unless that is chosen twice (auth.keyless and
# auth.allow_keyless_network): the desk has a veth up, and ttl=0 would not keep the LAN out.
set +e
in_ns desk "$build/services/compensator/hystloop-compensator" --config "$cfg/compensator.yaml" \
  --lcm-url "$foreign_url" --allow-network --rig "$prefix" --set auth.keyless=true --seconds 1 >"$out/keyless-refused.log" 2>&1
rc=$?
set -e
if [ "$rc" = 2 ] && grep -q "auth.keyless: a keyless service on a network other hosts reach" "$out/keyless-refused.log"; then
  echo "ok:   a keyless compensator on the desk's network is refused (exit 2, naming auth.allow_keyless_network)"
else echo "FAIL: a keyless compensator on a host network: exit $rc, $(head -c 300 "$out/keyless-refused.log")"; fail=1; fi
# The attacker chooses both.
in_ns desk timeout -s TERM 2 "$build/services/compensator/hystloop-compensator" --config "$cfg/compensator.yaml" \
  --lcm-url "$foreign_url" --allow-network --rig "$prefix" --set auth.keyless=true \
  --set auth.allow_keyless_network=true >"$out/foreign-compensator.log" 2>&1 || true
# The counts after: two more reports of each once the keyless compensator has ended, so one of
# them was composed after all the foreign traffic.
want_bridge=$(( $(reports bridge) + 2 )) want_compensator=$(( $(reports compensator) + 2 ))
reported_after() { [ "$(reports bridge)" -ge "$want_bridge" ] && [ "$(reports compensator)" -ge "$want_compensator" ]; }
wait_until 20 "two more reports of the bridge and of the compensator after the foreign traffic" reported_after
foreign_counts >"$out/foreign-after.txt"
value_in() { awk -F= -v k="$1" '$1 == k { print $2 }' "$2"; }
delta() { echo $(($(value_in "$1" "$out/foreign-after.txt") - $(value_in "$1" "$out/foreign-before.txt"))); }
foreign_check() {  # description, counter, minimum increase, maximum increase
  local d; d=$(delta "$2")
  if [ "$d" -ge "$3" ] && [ "$d" -le "$4" ]; then echo "ok:   keyless $1: $2 +$d"
  else echo "FAIL: keyless $1: $2 +$d (expected $3..$4)"; fail=1; fi
}
big=1000000000
foreign_check "ARM + START_EXPERIMENT (3 copies each)" bridge.control.rejected_unsigned 6 "$big"
foreign_check "command blocks" bridge.command.rejected_unsigned 1 "$big"
foreign_check "ARM + START_EXPERIMENT" compensator.control.rejected_unsigned 6 "$big"
foreign_check "trajectory (3 copies)" compensator.trajectory.rejected_unsigned 3 "$big"
foreign_check "parameter set (3 copies)" compensator.params.rejected_unsigned 3 "$big"
for k in bridge.control.accepted compensator.control.accepted compensator.trajectory.accepted \
  compensator.params.accepted compensator.params_accepted; do
  foreign_check "nothing accepted" "$k" 0 0
done
if [ "$(counter bridge state)" = 3 ]; then echo "ok:   the bridge stayed SAFE"
else echo "FAIL: the bridge left SAFE (state $(counter bridge state))"; fail=1; fi
complete_rows >"$out/foreign-sensor.csv"
moved=$(awk -F, -v s="$seq_before" 'NR > 1 && $1 > s && $3 != 0' "$out/foreign-sensor.csv" | wc -l)
ticks=$(awk -F, -v s="$seq_before" 'NR > 1 && $1 > s' "$out/foreign-sensor.csv" | wc -l)
if [ "$moved" = 0 ] && [ "$ticks" -gt 0 ]; then echo "ok:   u stayed 0 V over $ticks recorded ticks"
else echo "FAIL: u moved on $moved of $ticks recorded ticks"; fail=1; fi
