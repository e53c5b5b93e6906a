#!/usr/bin/env bash
# lcm-logger records what the project publishes; the log is read back by the project's
# endpoints, then lcm-logplayer plays it into a project subscriber: every message must
# arrive intact, once. Run inside tools/netns-run.
#   lcm_log_replay.sh <lcm_probe> [rounds]
source "$(dirname "$0")/lcm_common.sh" "$@"
rounds="${2:-300}"

echo "== record with lcm-logger"
# lcm-logger's subscription queue is LCM's default (30 messages): descheduled for ~15 ms by a busy
# machine it drops. As root it runs at a low SCHED_FIFO priority, as the project's own logger does.
rt=(); [ "$(id -u)" -eq 0 ] && command -v chrt >/dev/null && rt=(chrt -f 10)
"${rt[@]}" lcm-logger --quiet --force --flush-interval=20 --lcm-url="$url" --channel='HX_.*|WARMUP_.*' "$dir/run.lcmlog" &
logger=$!; pids+=("$logger")
# Warm-up sensor messages in the file so far (channel names are plain text in the log; none yet is
# 0, not a failure: grep's status would end the script under pipefail).
marks() { { grep -a -o 'WARMUP_SENSOR' "$dir/run.lcmlog" 2>/dev/null || true; } | wc -l; }
# lcm-logger gives no ready signal: warm-up rounds on another prefix until its file shows them
# (a fixed sleep lost the first rounds on a loaded machine; a non-empty file is not enough either:
# the first event can be in it before the round's sensor message; check-log counts these apart).
# One round per try: a busy machine can make lcm-logger drop a message (its queue holds 30).
warmup_recorded() {  # marks before
  "$probe" publish --url "$url" --prefix WARMUP_ --rounds 1 --rate-hz 1000 >/dev/null
  [ "$(marks)" -gt "$1" ]
}
wait_until 20 "lcm-logger recorded a warm-up round" warmup_recorded 0
# 1000 rounds/s: about the loop's own message rate.
"$probe" publish --url "$url" --prefix HX_ --rounds "$rounds" --rate-hz 1000
# The same at the end: the logger handles its socket in order, so once a round sent after them
# is in the file, so is every HX_ message.
wait_until 20 "lcm-logger recorded the closing warm-up round" warmup_recorded "$(marks)"
kill -INT "$logger"; wait "$logger" || true

echo "== read the log back"
"$probe" check-log --file "$dir/run.lcmlog" --prefix HX_ --rounds "$rounds" --ignore-prefix WARMUP_

echo "== play it with lcm-logplayer into a subscriber"
start_peer subscribe --url "$url" --prefix HX_ --rounds "$rounds" --timeout-s 8
lcm-logplayer --lcm-url="$url" --speed=1.0 "$dir/run.lcmlog"
wait "$peer"
