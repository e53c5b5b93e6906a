# Shared by the loop_*.sh / bridge_*.sh / compensator_*.sh integration tests (sourced).
# Usage in a test: source loop_common.sh "$@"  (args: bridge compensator loop_probe)
set -euo pipefail
bridge="$1"; compensator="$2"; probe="$3"
[ "${HYSTLOOP_NETNS:-0}" = 1 ] || { echo "run me inside tools/netns-run" >&2; exit 2; }
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
config="$here/../../deploy/config"
dir="$(mktemp -d)"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
  if [ "${KEEP_TEST_DIR:-0}" = 1 ]; then echo "test files kept in $dir"; else rm -rf "$dir"; fi
}
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; for f in "$dir"/*.log; do [ -f "$f" ] && { echo "== $f" >&2; tail -n 25 "$f" >&2; }; done; exit 1; }

# The tests share two CPUs with whatever else runs: the watchdog is widened from 2 ms to 0.2 s
# so that a stalled command path does not trip it by accident (stalls up to 80 ms were seen on a
# loaded 2-CPU VM, e.g. loopback multicast waits for ksoftirqd); what is checked is that it
# trips within watchdog_s + a few ticks when the commands stop, whatever watchdog_s is.
watchdog_s=0.2
bridge_args=(--config "$config/bridge.yaml" --set actuator.watchdog_s=$watchdog_s --set bridge.degraded_late_fraction=0.05)
compensator_args=(--config "$config/compensator.yaml" --set trajectory.shape=cosine --set trajectory.amplitude_m=-1.6e-6)

start_recording() {  # seconds
  "$probe" record --dir "$dir" --seconds "$1" >"$dir/probe.out" 2>&1 &
  pids+=($!)
  for _ in $(seq 100); do [ -e "$dir/recording" ] && return 0; sleep 0.02; done
  fail "the recorder did not start"
}
value() { "$probe" status-value --dir "$dir" --process "$1" --key "$2"; }
expect_value() {  # process key expected
  local v; v="$(value "$1" "$2")" || fail "$1 reports no $2"
  [ "$v" = "$3" ] || fail "$1 $2 = $v, expected $3"
}
