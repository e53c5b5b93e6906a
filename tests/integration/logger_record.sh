#!/usr/bin/env bash
# hystloop-logger records a stream of 10-tick blocks with a deliberate gap of 17 sensor
# blocks (170 ticks); stopped by SIGTERM it exits 0, the log holds every published message
# intact and in order, and the summary reports exactly that gap, in ticks, and no drop. lcm-logplayer then plays the log into a
# second logger, whose recording and summary must be the same. Run inside tools/netns-run.
#   logger_record.sh <hystloop-logger> <logger_probe>
source "$(dirname "$0")/logger_common.sh" "$@"
stream=(--blocks 5000 --block-ticks 10 --gap-at 1234 --gap-len 17 --commands 3000)

check_summary() {  # <summary.json> <stop reason>
  jq -e --arg reason "$2" '
    .stop_reason == $reason and
    .totals.dropped == 0 and .dropped.queue_full == 0 and .dropped.write_failed == 0 and
    .channels.HX_SENSOR.received == 4983 and .channels.HX_SENSOR.written == 4983 and
    .channels.HX_SENSOR.sequence.gap_events == 1 and .channels.HX_SENSOR.sequence.missing == 170 and
    .channels.HX_SENSOR.sequence.gaps == [[12340, 12509]] and
    .channels.HX_SENSOR.sequence.blocks == 4983 and .channels.HX_SENSOR.sequence.ticks == 49830 and
    .channels.HX_SENSOR.sequence.first_seq == 0 and .channels.HX_SENSOR.sequence.last_seq == 49999 and
    .channels.HX_SENSOR.sequence.duplicates == 0 and .channels.HX_SENSOR.sequence.out_of_order == 0 and
    .channels.HX_SENSOR.sequence.overlaps == 0 and .channels.HX_SENSOR.sequence.undecodable == 0 and
    .channels.HX_COMMAND.received == 3000 and .channels.HX_COMMAND.sequence.gap_events == 0 and
    .channels.HX_COMMAND.sequence.missing == 0 and .channels.HX_COMMAND.sequence.resumes == 0 and
    .channels.HX_COMMAND.sequence.first_seq == 500 and .channels.HX_COMMAND.sequence.last_seq == 30499 and
    .channels.HX_TRAJECTORY.written == 50 and .channels.HX_PARAMS.written == 50 and
    (.channels.HX_TRAJECTORY | has("sequence") | not) and
    (.files | length) == 1 and .files[0].events == .totals.written
  ' "$1" >/dev/null || { echo "summary $1 is not as expected:" >&2; cat "$1" >&2; exit 1; }
}

echo "== record (SIGTERM to stop)"
"$logger" --lcm-url "$url" --out-dir "$dir/a" --log-level warn &
pid=$!
"$probe" publish --url "$url" "${stream[@]}" --rate-hz 2000
# Stopped once it has received the whole stream (it answered a request sent after it).
"$probe" sync --url "$url" --wait-logger-s 20 || { echo "the logger did not answer after the stream" >&2; exit 1; }
kill -TERM "$pid"; rc=0; wait "$pid" || rc=$?; pid=""
[ "$rc" = 0 ] || { echo "logger exited $rc after SIGTERM" >&2; exit 1; }
files=("$dir"/a/hystloop-*.000.lcmlog)
[ "${#files[@]}" = 1 ] && [ -s "${files[0]}" ] || { echo "expected one log file: ${files[*]}" >&2; exit 1; }
summary="${files[0]%.000.lcmlog}.summary.json"

echo "== read it back"
"$probe" check-log "${stream[@]}" "${files[0]}"
check_summary "$summary" SIGTERM

echo "== play it with lcm-logplayer into a second logger (stopped by SIGINT)"
"$logger" --lcm-url "$url" --out-dir "$dir/b" --log-level warn &
pid=$!
"$probe" wait-logger --url "$url"
lcm-logplayer --lcm-url="$url" --speed=1.0 "${files[0]}"
"$probe" sync --url "$url" --wait-logger-s 20 || { echo "the logger did not answer after the replay" >&2; exit 1; }
kill -INT "$pid"; rc=0; wait "$pid" || rc=$?; pid=""
[ "$rc" = 0 ] || { echo "logger exited $rc after SIGINT" >&2; exit 1; }
replayed=("$dir"/b/hystloop-*.000.lcmlog)
"$probe" check-log "${stream[@]}" "${replayed[0]}"
check_summary "${replayed[0]%.000.lcmlog}.summary.json" SIGINT
echo "ok"
