#!/usr/bin/env bash
# tools/spy as a user runs it: a real lcm-spy window under Xvfb, joined to a stream of every
# hystloop channel; then a screenshot. Passes when the window is up, lcm-spy found all six
# hystloop types (so it decodes every channel) and the screenshot was written.
# Args: lcm_probe, types jar, screenshot path. Runs inside tools/netns-run.
set -euo pipefail
probe="$1" jar="$2" shot="$3"
display=":$((100 + RANDOM % 800))"
Xvfb "$display" -screen 0 1024x700x24 -nolisten tcp >/dev/null 2>&1 &
xvfb=$!
spy_out="$(mktemp)"
source "$(dirname "$0")/wait_common.sh"
cleanup() { kill "${spy:-}" "${pub:-}" "$xvfb" 2>/dev/null || true; rm -f "$spy_out"; }
trap cleanup EXIT
for _ in $(seq 50); do DISPLAY="$display" xwininfo -root >/dev/null 2>&1 && break; sleep 0.1; done
"$probe" publish --url 'udpm://239.255.76.67:7667?ttl=0' --prefix HX_ --rounds 4000 --rate-hz 400 >/dev/null 2>&1 &
pub=$!
DISPLAY="$display" HYSTLOOP_TYPES_JAR="$jar" "$(dirname "$0")/../../tools/spy" >"$spy_out" 2>&1 &
spy=$!
title=""
spy_window() {
  title="$(DISPLAY="$display" xwininfo -root -tree 2>/dev/null | grep -o '"LCM Spy"' || true)"
  [ -n "$title" ]
}
# Drawn: the screen is no longer the root window's black (Swing paints the window a while after
# it maps it; the mean over the screen is ~0.6 with the window drawn).
spy_drawn() {
  DISPLAY="$display" import -window root "$shot" 2>/dev/null &&
    awk -v m="$(identify -format '%[fx:mean]' "$shot" 2>/dev/null)" 'BEGIN { exit !(m > 0.3) }'
}
spy_fail() { echo "FAIL: $*; lcm-spy said: $(tr '\n' ' ' <"$spy_out")"; exit 1; }
wait_fail=spy_fail
wait_until 30 "an 'LCM Spy' window is up" spy_window
wait_until 30 "lcm-spy has drawn its window" spy_drawn
# The table's rows appear with the first messages, but its rate, jitter and bandwidth columns are
# averages lcm-spy updates once a second: the screenshot (for people, not checked) shows them run.
sleep 2  # a duration: two of lcm-spy's once-a-second rate updates
DISPLAY="$display" import -window root "$shot"
echo "window: ${title:-none}; lcm-spy said: $(tr '\n' ' ' <"$spy_out")"
[ -n "$title" ] || { echo "FAIL: no 'LCM Spy' window"; exit 1; }
grep -q "Found 9 LCM types" "$spy_out" || { echo "FAIL: lcm-spy did not load the 9 hystloop types"; exit 1; }
[ "$(head -c 8 "$shot" | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ] || { echo "FAIL: no PNG screenshot"; exit 1; }
echo "screenshot: $shot"
