#!/usr/bin/env bash
# The live loop with the re-identifier's automatic model choice on: bridge, compensator
# and re-identifier (reidentifier.models mem,pi,linear; a selection every 2 s), the compensator tracking
# the 1 Hz cosine with MEM from the configured (wrong for this stage) parameters. A model that beats
# MEM by the margin is published on HX_MODEL and adopted; then `hystloop-ctl pin-model` pins another
# model, which is switched to. Every change published is adopted (model_switches = model_changes)
# and the compensator refuses nothing (no invalid, stale, rejected or unknown set). Inside
# tools/netns-run.
#   model_choice.sh <hystloop-bridge> <hystloop-compensator> <loop_probe> <hystloop-reidentifier> <hystloop-ctl>
source "$(dirname "$0")/loop_common.sh" "$@"
reident="$4"; ctl="$5"
start_recording
# MEM from the start (the deployed compensator runs PI): the automatic choice then has a model to change.
"$compensator" "${compensator_args[@]}" --set compensator.mode=mem >"$dir/compensator.log" 2>&1 & cpid=$!; pids+=($cpid)
"$bridge" "${bridge_args[@]}" --auto-arm >"$dir/bridge.log" 2>&1 & bpid=$!; pids+=($bpid)
# The re-identifier logs to stdout (its --log-file is flushed late; the waits below read the log).
"$reident" --config "$config/reidentifier.yaml" --set reidentifier.models=mem,pi,linear --set reidentifier.model_period_s=2 \
  --set reidentifier.reversal_dead_band_V=1.0 >"$dir/reident.log" 2>&1 & rpid=$!; pids+=($rpid)
wait_log "$dir/compensator.log" "channels:"
wait_log "$dir/bridge.log" "started in the safe state"
wait_log "$dir/reident.log" "reidentifier: rate_hz"
# Automatic: the compensator starts with MEM; a model that beats it by the margin is published.
wait_for() {  # file text seconds
  for _ in $(seq $(( $3 * 20 ))); do grep -q -- "$2" "$1" 2>/dev/null && return 0; sleep 0.05; done
  fail "$1 never said '$2' within $3 s"
}
wait_for "$dir/reident.log" "published model change to" 20
first="$(grep -m1 -o 'published model change to [a-z]*' "$dir/reident.log" | awk '{print $NF}')"
pin=linear; [ "$first" = linear ] && pin=pi
# Pinned (hystloop-ctl pin-model): the pinned model is fitted and switched to, then no other.
"$ctl" pin-model "$pin" >"$dir/ctl.out" 2>&1 || { cat "$dir/ctl.out"; fail "hystloop-ctl pin-model $pin"; }
wait_for "$dir/reident.log" "model pinned to $pin" 5
wait_for "$dir/reident.log" "published model change to $pin" 20
# The swap waits for a reversal (every 0.5 s); the status reports come at 1 Hz: until the
# compensator reports every published change adopted and the pinned model running.
pin_adopted() {
  local changes; changes="$(status_key reidentifier model_changes)" || return 1
  [ "$changes" -ge 2 ] && [ "$(status_key compensator model_switches)" = "$changes" ] &&
    [[ "$(last_status compensator)" == *"detail=mode $pin,"* ]]
}
wait_until 20 "the compensator reported the pinned model $pin adopted" pin_adopted
"$probe" control --command shutdown
expect_shutdown 100 $bpid $cpid $rpid
stop_recording
grep "published model change\|model pinned" "$dir/reident.log" | sed 's/^.*info  //'
changes="$(value reidentifier model_changes)" || fail "no model_changes from the re-identifier"
[ "$changes" -ge 2 ] || fail "model_changes $changes, expected >= 2 (automatic, then pinned)"
expect_value compensator model_switches "$changes"  # every change published was adopted
for key in params_invalid params_stale params_rejected model_unknown_kind model_unknown_format \
           model.rejected_out_of_range model.rejected_non_finite model.rejected_decode_failed \
           params.rejected_out_of_range params.rejected_non_finite; do
  expect_value compensator "$key" 0
done
last="$(grep '^process=compensator' "$dir/status.log" | grep -v ' state=4 ' | tail -n 1)"
grep -q "detail=mode $pin," <<<"$last" || fail "the compensator does not run $pin: ${last##*detail=}"
expect_value bridge watchdog_trips 0
echo "model_choice: ok"
