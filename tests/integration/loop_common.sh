# Shared by the loop_*.sh / bridge_*.sh / compensator_*.sh integration tests (sourced).
# Usage in a test: source loop_common.sh "$@"  (args: bridge compensator loop_probe)
set -euo pipefail
bridge="$1"; compensator="$2"; probe="$3"
[ "${HYSTLOOP_NETNS:-0}" = 1 ] || { echo "run me inside tools/netns-run" >&2; exit 2; }
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# HYSTLOOP_CONFIG_DIR: another example of deploy/config (the two-mode stage, ...).
config="${HYSTLOOP_CONFIG_DIR:-$here/../../deploy/config}"
dir="$(mktemp -d)"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
  if [ "${KEEP_TEST_DIR:-0}" = 1 ]; then echo "test files kept in $dir"; else rm -rf "$dir"; fi
}
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; for f in "$dir"/*.log; do [ -f "$f" ] && { echo "== $f" >&2; tail -n 25 "$f" >&2; }; done; exit 1; }

# The product's defaults (deploy/config): the 2 ms watchdog on an empty command buffer, and the
# compensator planning compensator.horizon_s ahead, so a stall of the command path shorter than
# the horizon costs nothing. What the tests check does not depend on the machine being quiet:
# every applied voltage is safe, and a dead compensator trips the watchdog within
# horizon + watchdog_s (plans reach at most the horizon ahead; the trip follows the last planned
# tick by at most watchdog_s + a few ticks).
watchdog_s=0.002
horizon_s=$(sed -n 's/^ *horizon_s: *\([0-9.e-]*\).*/\1/p' "$config/compensator.yaml")
horizon_ticks=$(awk -v h="$horizon_s" 'BEGIN { printf "%d", h / 1e-4 + 0.5 }')
bridge_args=(--config "$config/bridge.yaml")
compensator_args=(--config "$config/compensator.yaml" --set trajectory.shape=cosine --set trajectory.amplitude_m=-1.6e-6)

# The recorder runs until stop_recording (at most 60 s), at a low SCHED_FIFO priority when
# allowed: starved for longer than its socket buffer it would lose samples.
start_recording() {
  "$probe" record --dir "$dir" --seconds 60 --rt-priority 10 >"$dir/probe.out" 2>&1 &
  recorder=$!; pids+=($recorder)
  for _ in $(seq 250); do [ -e "$dir/recording" ] && return 0; sleep 0.02; done
  fail "the recorder did not start"
}
stop_recording() { kill -TERM $recorder; wait $recorder || fail "the recorder failed"; }
# Waits (up to 20 s: sanitizer builds start slowly) until a log file says something.
wait_log() {  # file text
  for _ in $(seq 400); do grep -q -- "$2" "$1" 2>/dev/null && return 0; sleep 0.05; done
  fail "$1 never said '$2'"
}
value() { "$probe" status-value --dir "$dir" --process "$1" --key "$2"; }
# A service's --help names each of the options given.
expect_help() {  # executable option...
  local exe="$1"; shift
  "$exe" --help >"$dir/help.txt" || fail "--help exited with $?"
  for opt in "$@"; do
    grep -q -- "$opt" "$dir/help.txt" || fail "--help does not mention $opt"
  done
}
# A command line a service refuses: it exits 2 and its stderr says the expected text.
expect_refused() {  # executable expected-text args...
  local exe="$1" want="$2"; shift 2
  set +e; "$exe" "$@" >"$dir/out.txt" 2>"$dir/err.txt"; local rc=$?; set -e
  [ $rc -eq 2 ] || fail "'$*' exited with $rc, expected 2 ($(cat "$dir/err.txt"))"
  grep -q -- "$want" "$dir/err.txt" || fail "'$*': stderr does not say '$want': $(cat "$dir/err.txt")"
}
# After a SHUTDOWN request: each process stops within tenths/10 s and exits 0.
expect_shutdown() {  # tenths-of-a-second pid...
  local tenths="$1" p; shift
  for p in "$@"; do
    for _ in $(seq "$tenths"); do kill -0 $p 2>/dev/null || break; sleep 0.1; done
    kill -0 $p 2>/dev/null && fail "pid $p did not stop on SHUTDOWN"
    wait $p || fail "pid $p exited with $?"
  done
}
# Stops the recorder and runs loop_probe analyze on its recording: the figures go to
# $dir/analysis.txt (read them with get) and are printed; an unsafe sample fails with the text given.
stop_and_analyze() {  # failure-text
  stop_recording
  "$probe" analyze --dir "$dir" --watchdog $watchdog_s >"$dir/analysis.txt" || { cat "$dir/analysis.txt"; fail "$1"; }
  cat "$dir/analysis.txt"
}
get() { sed -n "s/^$1=//p" "$dir/analysis.txt"; }
# No command of the recording was planned further ahead than the horizon (ticks).
expect_within_horizon() {
  [ "$(get max_planned_ahead_ticks)" -le "$horizon_ticks" ] ||
    fail "a command was planned $(get max_planned_ahead_ticks) ticks ahead (horizon $horizon_ticks)"
}
expect_value() {  # process key expected
  local v; v="$(value "$1" "$2")" || fail "$1 reports no $2"
  [ "$v" = "$3" ] || fail "$1 $2 = $v, expected $3"
}

# Bounded waits on a condition instead of fixed sleeps: wait_until (wait_common.sh) fails
# through fail() above, naming what did not happen.
source "$here/wait_common.sh"
# The last report (not STOPPING) of a process in the recorder's status.log, as status-value reads it.
last_status() {  # process
  awk -v p="process=$1 " 'index($0, p) == 1 && index($0, " state=4 ") == 0 { last = $0 } END { print last }' \
    "$dir/status.log" 2>/dev/null
}
# True when the last report of a process has each key at or above its value (the counters).
status_at_least() {  # process key min [key min]...
  local line; line="$(last_status "$1")"; shift
  [ -n "$line" ] || return 1
  awk -v line="${line% detail=*}" -v want="$*" 'BEGIN {
    n = split(line, w, " "); for (i = n; i >= 1; i--) { eq = index(w[i], "="); v[substr(w[i], 1, eq - 1)] = substr(w[i], eq + 1) }
    m = split(want, k, " "); for (i = 1; i < m; i += 2) if (!(k[i] in v) || v[k[i]] + 0 < k[i + 1] + 0) exit 1
  }'
}
# One value of the last report of a process (the first of duplicate names, as status-value).
status_key() {  # process key
  local line; line="$(last_status "$1")"
  awk -v line="${line% detail=*}" -v k="$2" 'BEGIN {
    n = split(line, w, " "); for (i = 1; i <= n; i++) if (index(w[i], k "=") == 1) { print substr(w[i], length(k) + 2); exit 0 }
    exit 1 }'
}
# How many reports (STOPPING ones too) a process has sent so far.
status_reports() { grep -c "^process=$1 " "$dir/status.log" 2>/dev/null || true; }
# Waits for count more reports of a process after now: with count 2, one of them was composed after
# whatever happened before the call (the first may have been on its way already).
wait_reports() {  # process count description
  local want=$(( $(status_reports "$1") + $2 ))
  wait_until 20 "$3 ($2 more status reports of $1)" status_reports_reach "$1" "$want"
}
status_reports_reach() { [ "$(status_reports "$1")" -ge "$2" ]; }
# True when the recorder's command.csv has grown beyond a size (bytes): it is written in 4 kB
# chunks, so growth means commands were published (by the compensator) after the size was taken.
commands_recorded() { [ "$(stat -c %s "$dir/command.csv" 2>/dev/null || echo 0)" -gt "$1" ]; }
# True when the recorder has written at least n samples to sensor.csv (written in 4 kB chunks: a
# few dozen behind what it received).
samples_recorded() { [ $(( $(wc -l 2>/dev/null <"$dir/sensor.csv" || echo 1) - 1 )) -ge "$1" ]; }
# True when the recorder has a process's STOPPING report: the bridge publishes it after its last
# sensor block and the recorder handles its socket in order, so every block is recorded by then.
stopping_reported() { grep -q "^process=$1 state=4 " "$dir/status.log" 2>/dev/null; }
