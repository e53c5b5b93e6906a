#!/usr/bin/env bash
# hystloop-ctl's requests answered by the live services: bridge, compensator and re-identifier
# (the product's configs). With no rig running a request says so (exit 1). Then each request is
# confirmed by the process it is for, on HX_STATUS: arm (armed), a partial gains change (only kp
# changes; the gains in force are printed), mode, hold (the re-identifier keeps fitting and
# publishes nothing: a hand-sent set stays in use while it refits), release, disarm; a
# pin-model the re-identifier cannot honour (reidentifier.models off) and a request for a process
# that does not exist each exit 1 naming why; shutdown to all is confirmed by every process.
# Inside tools/netns-run.
#   ctl_acks.sh <hystloop-bridge> <hystloop-compensator> <loop_probe> <hystloop-reidentifier> <hystloop-ctl>
source "$(dirname "$0")/loop_common.sh" "$@"
reident="$4"; ctl="$5"
# Runs ctl, keeping stdout and stderr in $dir/ctl.out; expects exit $1.
expect_ctl() {  # exit-status args...
  local want="$1" rc=0; shift
  "$ctl" "$@" >"$dir/ctl.out" 2>&1 || rc=$?
  [ "$rc" = "$want" ] || fail "hystloop-ctl $* exited $rc, expected $want: $(cat "$dir/ctl.out")"
}
says() { grep -q -- "$1" "$dir/ctl.out" || fail "hystloop-ctl did not say '$1': $(cat "$dir/ctl.out")"; }

expect_ctl 1 arm --timeout 1
says "no rig is running"

start_recording
"$compensator" "${compensator_args[@]}" >"$dir/compensator.log" 2>&1 & cpid=$!; pids+=($cpid)
"$bridge" "${bridge_args[@]}" >"$dir/bridge.log" 2>&1 & bpid=$!; pids+=($bpid)
"$reident" --config "$config/reidentifier.yaml" >"$dir/reident.log" 2>&1 & rpid=$!; pids+=($rpid)
wait_log "$dir/compensator.log" "channels:"
wait_log "$dir/bridge.log" "started in the safe state"
wait_log "$dir/reident.log" "reidentifier: rate_hz"

expect_ctl 0 arm
says "'bridge' confirmed"
expect_ctl 0 gains
says "servo gains in force: kp "
before="$(grep -o 'ki [^,]*' "$dir/ctl.out")"
expect_ctl 0 gains --kp 0.05
says "servo gains in force: kp 0.05, $before"  # ki as it was: only kp changed
expect_ctl 2 gains --kp 5  # past kp <= 2: refused before anything is sent
expect_ctl 0 mode linear
says "'compensator' confirmed"
expect_ctl 0 mode pi

expect_ctl 1 pin-model mem
says "'reidentifier' refused it: reidentifier.models is off"
expect_ctl 1 disarm --target nobody --timeout 1
says "'nobody' sent no status report"

# Held: a hand-sent set stays in use while the re-identifier refits (refit_period_s 1 s) and
# publishes nothing; released, it publishes again.
expect_ctl 0 mode mem
expect_ctl 0 hold on
# Counted once the hold is confirmed: before it, the re-identifier publishes what beats the set in use.
attempted_before="$(value reidentifier refits_attempted)" || fail "no refits_attempted"
published_before="$(grep -c "published params version" "$dir/reident.log" || true)"
says "'reidentifier' confirmed"
expect_ctl 0 params --c1 6.0e-9 --c2 1e-12 --c3 1.2
says "adopted parameters v"
held_version="$(grep -o 'adopted parameters v[0-9]*' "$dir/ctl.out" | grep -o '[0-9]*$')"
grep -q "note: the re-identifier runs and is not holding" "$dir/ctl.out" && fail "ctl params warned although held"
# Held while it refits with the set in use: a refit finished after a report composed after the
# set was adopted (a refit the hold did not hold back would be published and replace the set).
wait_reports reidentifier 2 "a re-identifier report after the set was adopted"
attempted_with_set="$(status_key reidentifier refits_attempted)" || fail "no refits_attempted"
wait_until 30 "the re-identifier finished a refit with the operator's set in use" \
  status_at_least reidentifier refits_attempted $((attempted_with_set + 1))
expect_value reidentifier params_held 1
expect_value compensator params_version "$held_version"
[ "$(grep -c "published params version" "$dir/reident.log" || true)" = "$published_before" ] ||
  fail "the re-identifier published while held: $(grep "published params version" "$dir/reident.log" | tail -n 1)"
held="$(value reidentifier refits_held)" || fail "no refits_held"
attempted="$(value reidentifier refits_attempted)" || fail "no refits_attempted"
[ "$attempted" -gt "$attempted_before" ] || fail "the re-identifier stopped fitting while held ($attempted refits)"
echo "ctl_acks: $((attempted - attempted_before)) refits while held ($held better than the set in use, held back);" \
  "the operator's v$held_version stayed in use"
expect_ctl 0 hold off
expect_value_soon() { for _ in $(seq 40); do [ "$(value "$1" "$2" 2>/dev/null)" = "$3" ] && return 0; sleep 0.1; done; expect_value "$@"; }
expect_value_soon reidentifier params_held 0

expect_ctl 0 disarm
says "'bridge' confirmed"
expect_ctl 0 shutdown
for p in compensator bridge reidentifier; do says "'$p' confirmed"; done
expect_shutdown 100 $bpid $cpid $rpid
stop_recording
echo "ctl_acks: ok"
