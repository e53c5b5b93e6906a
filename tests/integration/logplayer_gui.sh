#!/usr/bin/env bash
# tools/logplayer-gui as a user runs it: LCM's log player window under Xvfb plays a log of every
# hystloop channel, and a subscriber receives each message of it intact, once (Debian's own
# lcm-logplayer-gui does not start on Java 17). Runs inside tools/netns-run.
# Args: lcm_probe, types jar, work dir.
set -euo pipefail
probe="$1" jar="$2" work="$3"
rounds=50
rm -rf "$work"; mkdir -p "$work"
"$probe" write-log --file "$work/run.lcmlog" --prefix HX_ --rounds "$rounds"
display=":$((100 + RANDOM % 800))"
Xvfb "$display" -screen 0 1024x700x24 -nolisten tcp >/dev/null 2>&1 &
xvfb=$!
cleanup() { kill "${player:-}" "$xvfb" 2>/dev/null || true; }
trap cleanup EXIT
for _ in $(seq 50); do DISPLAY="$display" xwininfo -root >/dev/null 2>&1 && break; sleep 0.1; done
"$probe" subscribe --url 'udpm://239.255.76.67:7667?ttl=0' --prefix HX_ --rounds "$rounds" --timeout-s 30 \
  --ready-file "$work/ready" >"$work/subscriber.out" 2>&1 &
sub=$!
for _ in $(seq 100); do [ -e "$work/ready" ] && break; sleep 0.05; done
[ -e "$work/ready" ] || { echo "FAIL: the subscriber never became ready"; exit 1; }
DISPLAY="$display" HYSTLOOP_TYPES_JAR="$jar" "$(dirname "$0")/../../tools/logplayer-gui" "$work/run.lcmlog" \
  >"$work/player.out" 2>&1 &
player=$!
if ! wait "$sub"; then
  echo "FAIL: the subscriber did not receive the log intact: $(tr '\n' ' ' <"$work/subscriber.out")"
  echo "player said: $(tr '\n' ' ' <"$work/player.out")"
  exit 1
fi
kill -0 "$player" 2>/dev/null || { echo "FAIL: the player exited: $(tr '\n' ' ' <"$work/player.out")"; exit 1; }
echo "logplayer-gui played $rounds rounds of every channel: $(tail -n 3 "$work/subscriber.out" | tr '\n' ' ')"
