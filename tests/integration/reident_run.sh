#!/usr/bin/env bash
# hystloop-reidentifier end to end. Run inside tools/netns-run (udpm, ttl=0).
#   reident_run.sh cli     <hystloop-reidentifier> <reident_stream> <source dir>
#       --help; bad configuration exits 2 naming the field; SIGTERM exits 0 within 1 s;
#       control_t SHUTDOWN exits 0
#   reident_run.sh good    <...same...>   refit of a plant whose gain moved 10 % is published
#   reident_run.sh garbage <...same...>   NaN / constant u / stuck y never publish a set
#   reident_run.sh invalid <...same...>   with --publish-invalid, refused refits go out as valid = false
#   reident_run.sh axis    <...same...>   --axis y on blocks of x and y: fits y's, as "reidentifier-y",
#                                         its sets carry y; a bad axis exits 2 naming --axis / the key
set -euo pipefail
what="$1"; reident="$2"; stream="$3"; src="$4"
url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
config="$src/deploy/config/reidentifier.yaml"
[ "${HYSTLOOP_NETNS:-0}" = 1 ] || { echo "run me inside tools/netns-run" >&2; exit 2; }
dir="$(mktemp -d)"; pid=""
cleanup() { [ -n "$pid" ] && kill -KILL "$pid" 2>/dev/null; rm -rf "$dir"; }
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; [ -f "$dir/reident.log" ] && tail -n 30 "$dir/reident.log" >&2; exit 1; }

# True while the process runs (an exited child stays a zombie until waited for).
alive() { local st; st="$(ps -o stat= -p "$1" 2>/dev/null)" || return 1; [[ "$st" != Z* ]]; }
# Starts the re-identifier in the background with extra arguments.
start() {
  "$reident" --config "$config" --lcm-url "$url" --log-file "$dir/reident.log" "$@" >"$dir/stdout" 2>"$dir/stderr" &
  pid=$!
}
# SIGTERM; it must exit 0 within 1 s.
stop_within_1s() {
  local t0 t1 rc
  t0=$(date +%s%N)
  kill -TERM "$pid"
  rc=0; wait "$pid" || rc=$?
  t1=$(date +%s%N)
  pid=""
  local ms=$(( (t1 - t0) / 1000000 ))
  echo "SIGTERM -> exit $rc in $ms ms"
  [ "$rc" = 0 ] || fail "exit status $rc after SIGTERM"
  [ "$ms" -le 1000 ] || fail "took $ms ms to stop"
  grep -q "stopping:" "$dir/reident.log" || fail "no stop summary in the log"
}

check_bad() {  # expected-field args...
  local field="$1"; shift
  local rc=0
  "$reident" "$@" >/dev/null 2>"$dir/err" || rc=$?
  [ "$rc" = 2 ] || fail "exit $rc (want 2) for $*"
  grep -qF -- "$field" "$dir/err" || fail "stderr does not name $field: $(cat "$dir/err")"
  echo "refused ($*): $(cat "$dir/err")"
}

case "$what" in
  cli)
    "$reident" --help >"$dir/help" || fail "--help exit status"
    for w in --config --set --lcm-url --rig --publish-invalid reidentifier.refit_period_s mem.; do
      grep -q -- "$w" "$dir/help" || fail "--help does not mention $w"
    done
    check_bad "reidentifier.refit_period_s" --set reidentifier.refit_period_s=-1
    check_bad "reidentifier.capacity_s" --set reidentifier.window_s=5 --set reidentifier.capacity_s=2
    check_bad "mem.c1" --set mem.c1=0
    printf 'reidentifier:\n  window_sec: 2\n' >"$dir/typo.yaml"
    check_bad "reidentifier.window_sec" --config "$dir/typo.yaml"
    # Refused before LCM starts; and this runs inside tools/netns-run, so nothing could leave anyway.
    check_bad "lcm.url" --lcm-url "udpm://239.255.76.67:7667?ttl=1"
    check_bad "reidentifier.lcm_queue" --set reidentifier.lcm_queue=10
    start
    # Stopped once it serves (its first HX_STATUS), as a running re-identifier is.
    "$stream" status --url "$url" || fail "no HX_STATUS from the re-identifier: $(cat "$dir/stderr")"
    kill -0 "$pid" || fail "exited early: $(cat "$dir/stderr")"
    stop_within_1s
    grep -q "reidentifier: rate_hz 10000" "$dir/reident.log" || fail "configuration not logged at start"
    # control_t SHUTDOWN addressed to "reidentifier" stops it as SIGTERM does.
    start
    "$stream" shutdown --url "$url" || fail "could not send SHUTDOWN"
    for _ in $(seq 20); do alive "$pid" || break; sleep 0.05; done
    ! alive "$pid" || fail "still running 1 s after SHUTDOWN"
    rc=0; wait "$pid" || rc=$?; pid=""
    [ "$rc" = 0 ] || fail "exit status $rc after SHUTDOWN"
    grep -q "shutdown requested" "$dir/reident.log" || fail "SHUTDOWN not logged"
    ;;
  good)
    start
    "$stream" good --url "$url" --duration-s 6 --frequency-hz 1 --tolerance 0.03 || fail "stream check"
    stop_within_1s
    grep -q "published params version" "$dir/reident.log" || fail "no 'published' log line"
    ;;
  invalid)
    start --publish-invalid
    "$stream" good --url "$url" --duration-s 6 --frequency-hz 1 --tolerance 0.03 --expect-invalid 1 || fail "stream check"
    stop_within_1s
    ;;
  garbage)
    start --set reidentifier.window_s=1 --set reidentifier.refit_period_s=0.5
    "$stream" garbage --url "$url" --phase-s 2 || fail "stream check"
    stop_within_1s
    grep -q "refit refused (poisoned_window)" "$dir/reident.log" || fail "refusals not logged"
    ! grep -q "published params" "$dir/reident.log" || fail "a set was published"
    ;;
  axis)
    "$reident" --help | grep -q -- "--axis" || fail "--help does not mention --axis"
    check_bad "--axis" --axis w
    check_bad "reidentifier.axis" --set reidentifier.axis=w
    start --axis y
    "$stream" good --axis y --url "$url" --duration-s 6 --frequency-hz 1 --tolerance 0.03 || fail "stream check"
    stop_within_1s
    grep -q 'axis: y (process "reidentifier-y"' "$dir/reident.log" || fail "the axis is not logged at start"
    grep -q "reidentifier-y\[" "$dir/reident.log" || fail "the log does not name the process reidentifier-y"
    grep -q "published params version" "$dir/reident.log" || fail "no 'published' log line"
    ;;
  *) echo "usage: reident_run.sh cli|good|invalid|garbage|axis <reidentifier> <stream> <source dir>" >&2; exit 2 ;;
esac
echo "reident_run.sh $what: OK"
