#!/usr/bin/env bash
# The rig spread over three hosts, as a lab runs it with deploy/rig.yaml and `deploy/hystloop up
# --host NAME`: three network namespaces (each its own host name) joined by veth pairs to a
# Linux bridge, multicast routed on each veth, ttl=1 in the URL:
#   stage   (bridge, logger)      control (compensator, reidentifier)
#   desk    (hystloop-ctl, loop_probe recording every message: the spy's stand-in)
# Phase 1, the demo's scenario across them (deploy/hystloop scenario from the desk), judged on the
# log as the one-host demo is (summary_checks.sh), plus no logger gap. Phase 2, while the loop
# runs: the compensator moves from "control" to "desk" (down there, up here with a rig file that
# says so); the bridge rides through on its buffer or goes safe, never outside its limits (every
# tick of the logger's log: u within actuator.u_min_V/u_max_V, every step within the slew or the
# safe ramp, a trip within watchdog_s of the last command); re-armed, the loop tracks again with
# the compensator reporting from "desk". The desk's listener must have heard every process. Everything runs inside the private namespace of
# tools/netns-run (the bridge and the namespaces are its children): nothing touches the host's
# network, and all of it goes when the test exits.
#   rig_hosts.sh <source dir> <build dir> <loop_probe> <output dir>
set -euo pipefail
src="$1" build="$2" probe="$3" out="$4"
[ "${HYSTLOOP_NETNS:-0}" = 1 ] || { echo "run me inside tools/netns-run" >&2; exit 2; }
source "$(dirname "$0")/summary_checks.sh"
source "$(dirname "$0")/wait_common.sh"; wait_fail=die  # fail is the count of failed checks here
rm -rf "$out"; mkdir -p "$out"
sfx=$$ prefix=HXR_ br="hxbr$$"
declare -A holder=()
fail=0
cleanup() {
  set +e
  local f
  for f in "$out"/run-*/*.pid; do [ -f "$f" ] && kill -KILL "$(cat "$f")" 2>/dev/null; done
  [ -n "${recorder:-}" ] && kill -KILL "$recorder" 2>/dev/null
  for h in "${holder[@]}"; do kill -KILL "$h" 2>/dev/null; done
  ip link del "$br" 2>/dev/null
  true
}
trap cleanup EXIT
die() {
  echo "FAIL: $*" >&2
  for f in "$out"/run-*/*.log; do [ -f "$f" ] && { echo "== $f" >&2; tail -n 15 "$f" >&2; }; done
  exit 1
}

# --- three hosts on one bridge -------------------------------------------------------------
in_ns() { local n="$1"; shift; nsenter -t "${holder[$n]}" -n -u -- "$@"; }
ip link add "$br" type bridge
ip link set "$br" type bridge mcast_snooping 0  # flood multicast to every port (no IGMP querier here)
ip link set "$br" up
i=0
for n in stage control desk; do
  i=$((i + 1))
  unshare -n -u sh -c "hostname $n && exec sleep 600" &
  holder[$n]=$!
  for _ in $(seq 100); do
    [ "$(readlink "/proc/${holder[$n]}/ns/net")" != "$(readlink /proc/self/ns/net)" ] &&
      [ "$(nsenter -t "${holder[$n]}" -u hostname 2>/dev/null)" = "$n" ] && break
    sleep 0.02
  done
  ip link add "hx${n:0:1}$sfx" type veth peer name "hx${n:0:1}n$sfx"
  ip link set "hx${n:0:1}$sfx" master "$br" up
  ip link set "hx${n:0:1}n$sfx" netns "${holder[$n]}"
  in_ns "$n" ip link set lo up
  in_ns "$n" ip link set "hx${n:0:1}n$sfx" name eth0
  in_ns "$n" ip addr add "10.203.0.$i/24" dev eth0
  in_ns "$n" ip link set eth0 multicast on up
  in_ns "$n" ip route add 224.0.0.0/4 dev eth0
done
echo "hosts: stage, control, desk on bridge $br (10.203.0.1-3/24)"

# --- the rig files: the demo's configs, ttl=1; the second one with the compensator on the desk --
cfg="$src/deploy/config/demo"
ctl_exe="$(find "$build/tools/ctl" -maxdepth 1 -name hystloop-ctl -type f)"
ctl_get() { "$ctl_exe" config-get "$@"; }
# A keyed rig (rig.key_file) where hystloop-ctl has keygen (docs/SECURITY.md).
key_line=""
if "$ctl_exe" keygen --help >/dev/null 2>&1; then
  "$ctl_exe" keygen --out "$out/rig.key" >/dev/null || die "keygen"
  key_line="  key_file: $out/rig.key"
  echo "keyed rig: $out/rig.key"
else
  echo "keyless rig: this hystloop-ctl has no keygen (the foreign-publisher check is skipped)"
fi
rig_file() {  # file, host of the compensator
  local comp_control="" comp_desk=""
  if [ "$2" = control ]; then comp_control="compensator, "; else comp_desk="compensator"; fi
  cat >"$1" <<EOF
rig:
  prefix: $prefix
  lcm_url: "udpm://239.255.76.67:7667"
  ttl: 1
  config_dir: $cfg
$key_line
hosts:
  stage: {services: [bridge, logger]}
  control: {services: [${comp_control}reidentifier]}
  desk: {services: [$comp_desk]}
EOF
}
rig_file "$out/rig.yaml" control
rig_file "$out/rig-moved.yaml" desk
hy() {  # host, rig file, deploy/hystloop arguments...
  local n="$1" f="$2"; shift 2
  in_ns "$n" "$src/deploy/hystloop" --no-build --build-dir "$build" --host "$n" --rig-file "$f" \
    --run-dir "$out/run-$n" "$@"
}

# --- phase 1: the demo's scenario across the hosts -----------------------------------------
mkdir -p "$out/desk"  # before the recorder starts: it opens its files there at once
nsenter -t "${holder[desk]}" -n -u -- "$probe" --url "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304" --prefix "$prefix" \
  record --dir "$out/desk" --seconds 900 --rt-priority 10 >"$out/desk-record.txt" 2>&1 &
recorder=$!  # the probe itself (nsenter execs it): SIGTERM ends the recording
wait_until 20 "the desk's recorder started ($out/desk-record.txt)" test -e "$out/desk/recording"
LOG_DIR="$out/log1" hy stage "$out/rig.yaml" up || die "up --host stage"
hy control "$out/rig.yaml" up || die "up --host control"
hy desk "$out/rig.yaml" status || die "status does not show every service on its host"
if [ -n "$key_line" ]; then
  source "$(dirname "$0")/rig_hosts_foreign.sh"  # a keyless publisher on the desk: refused, counted
fi
hy desk "$out/rig.yaml" scenario --seconds 12 || die "the scenario failed"
hy stage "$out/rig.yaml" down logger || die "down logger"
"$build/tools/report/hystloop-report" "$out/log1"/*.lcmlog --out "$out/phase1" --rig "$prefix" --no-plots --quiet ||
  die "report of phase 1"
s1="$out/phase1/summary.json"
check_loop_summary "$s1" "$prefix"
summary_check "$s1" "no logger gap across the hosts" '.logger_gaps == 0 and .seq_gaps == 0'
print_loop_summary "$s1"

# --- phase 2: the compensator moves from "control" to "desk" while the loop runs -------------
LOG_DIR="$out/log2" hy stage "$out/rig.yaml" up logger || die "up logger again"
sleep 2  # a duration: the loop tracks, recorded by the new logger, before the compensator moves
t_move=$(date +%s.%N)
hy control "$out/rig.yaml" down compensator || die "down compensator on control"
hy desk "$out/rig-moved.yaml" up || die "up --host desk (the compensator)"
echo "compensator moved control -> desk in $(awk -v a="$t_move" -v b="$(date +%s.%N)" 'BEGIN { printf "%.2f", b - a }') s"
# `up` returned once the moved compensator reported from the desk; status listens 2.5 s itself.
hy desk "$out/rig-moved.yaml" status >"$out/status-moved.txt" 2>&1 || { cat "$out/status-moved.txt"; die "status after the move"; }
grep -Eq '^compensator +desk +desk ' "$out/status-moved.txt" || { cat "$out/status-moved.txt"; die "the compensator does not report from desk"; }
echo "ok:   status shows the compensator on desk"
# A trip (the buffer ran dry while no compensator ran) leaves the bridge safe until ARM.
hy desk "$out/rig-moved.yaml" ctl arm >/dev/null
hy desk "$out/rig-moved.yaml" ctl trajectory --mem-paper --blend 0.5 >/dev/null
hy desk "$out/rig-moved.yaml" ctl watch --seconds 8
hy stage "$out/rig.yaml" down || die "down --host stage"
hy desk "$out/rig-moved.yaml" down || die "down --host desk"
hy control "$out/rig.yaml" down || die "down --host control"
kill -TERM "$recorder"; wait "$recorder" || die "the desk's recorder failed ($(cat "$out/desk-record.txt"))"
recorder=""
"$build/tools/report/hystloop-report" "$out/log2"/*.lcmlog --out "$out/phase2" --rig "$prefix" --no-plots --quiet \
  --csv SENSOR ||
  die "report of phase 2"
s2="$out/phase2/summary.json"
print_loop_summary "$s2"
summary_check "$s2" "after the move: no sample tick missing" '.missing_samples == 0'
summary_check "$s2" "after the move: tracking again within 10 nm RMS in the last 5 s" '.rms_error_last_5s_m < 10e-9'
for p in bridge logger compensator reidentifier; do
  grep -q "^process=$p " "$out/desk/status.log" && echo "ok:   the desk's listener heard $p" ||
    { echo "FAIL: the desk's listener never heard $p"; fail=1; }
done

# Every tick of the phase-2 log (the report's CSV export) in loop_probe's layout
# (seq,utime,u_V,y_m,flags,y_ref_m,u_ff_V,u_fb_V), checked against the bridge's config (the
# demo's, over the product defaults).
mkdir -p "$out/log2-ticks"
awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; print "seq,utime,u_V,y_m,flags,y_ref_m,u_ff_V,u_fb_V"; next }
  { print $c["seq"] "," $c["utime_us"] "," $c["u_V"] "," $c["y_m"] "," $c["flags"] "," $c["y_ref_m"] "," \
          $c["u_ff_V"] "," $c["u_fb_V"] }' "$out/phase2/${prefix}SENSOR.csv" >"$out/log2-ticks/sensor.csv"
limit() { ctl_get "$cfg/bridge.yaml" "$1" --default "$(ctl_get "$src/deploy/config/bridge.yaml" "$1")"; }
if "$probe" analyze --dir "$out/log2-ticks" --u-min "$(limit actuator.u_min_V)" --u-max "$(limit actuator.u_max_V)" \
    --slew "$(limit actuator.slew_V_per_s)" --ramp "$(limit actuator.safe_ramp_V_per_s)" \
    --watchdog "$(limit actuator.watchdog_s)" >"$out/analysis.txt"; then
  echo "ok:   every applied u within [$(limit actuator.u_min_V), $(limit actuator.u_max_V)] V, slew and trips in bounds"
else
  echo "FAIL: the bridge left its limits"; fail=1
fi
cat "$out/analysis.txt"
exit "$fail"
