#!/usr/bin/env bash
# The replay regression notices a change: the golden log with one command's u_ff_V moved by one
# ulp must fail the exact comparison (exit 1) naming that tick, and pass within a tolerance.
# Run inside tools/netns-run.
#   replay_altered.sh <source dir> <build dir>
set -euo pipefail
src="$1"; build="$2"
[ "${HYSTLOOP_NETNS:-0}" = 1 ] || { echo "run me inside tools/netns-run" >&2; exit 2; }
filter="$(find "$build/tools" -maxdepth 2 -type f -name hystloop-replay-filter | head -n 1)"
[ -n "$filter" ] || { echo "hystloop-replay-filter is not built in $build" >&2; exit 2; }
golden="$src/tests/data/golden-loop.lcmlog"
config="$src/tests/data/golden-loop.compensator.yaml"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

echo "== alter the 1000th command of the golden log by one ulp"
"$filter" alter "$golden" "$work/altered.lcmlog" --nth 1000 | tee "$work/alter.txt"
tick="$(sed -n 's/^altered tick \([0-9]*\):.*/\1/p' "$work/alter.txt")"
[ -n "$tick" ] || { echo "FAIL: the filter did not name the altered tick" >&2; exit 1; }

echo "== exact replay: must fail at tick $tick"
set +e
"$src/tools/replay-check" --build "$build" --config "$config" "$work/altered.lcmlog" | tee "$work/exact.txt"
rc=${PIPESTATUS[0]}
set -e
[ "$rc" = 1 ] || { echo "FAIL: replay-check exited $rc, expected 1 (divergence)" >&2; exit 1; }
grep -q "FIRST DIVERGENCE at tick $tick (answering sample [0-9]*): u_ff_V expected" "$work/exact.txt" \
  || { echo "FAIL: the report does not name tick $tick and u_ff_V" >&2; exit 1; }
grep -q "1 differing" "$work/exact.txt" || { echo "FAIL: more than the altered tick differs" >&2; exit 1; }

echo "== within --tolerance-V 1e-9: must pass"
"$src/tools/replay-check" --build "$build" --config "$config" --tolerance-V 1e-9 "$work/altered.lcmlog" \
  || { echo "FAIL: one ulp is within 1 nV, yet the replay failed" >&2; exit 1; }
echo "PASS"
