#!/usr/bin/env bash
# The exit-code contract of every program (core/cli.hpp): --help exits 0 and prints a usage; an
# unknown option and a malformed value exit 2 (not CLI11's own 105, 106, ...) with a message on
# stderr. No program gets far enough to open LCM or a device.
#   exit_codes.sh <program>...
set -u
failed=0
check() {  # check <want> <program> <args...>
  local want=$1 prog=$2
  shift 2
  local out rc
  out=$("$prog" "$@" 2>&1 </dev/null)
  rc=$?
  if [ "$rc" -ne "$want" ]; then
    echo "FAIL: $(basename "$prog") $*: exit $rc, want $want"
    printf '%s\n' "$out" | head -5 | sed 's/^/    /'
    failed=1
  fi
  if [ "$want" -eq 0 ] && [ "$rc" -eq 0 ] && ! grep -qi "usage\|options" <<<"$out"; then
    echo "FAIL: $(basename "$prog") $*: no usage printed"
    failed=1
  fi
  if [ "$want" -eq 2 ] && [ "$rc" -eq 2 ] && [ -z "$out" ]; then
    echo "FAIL: $(basename "$prog") $*: exit 2 without a message"
    failed=1
  fi
}
[ $# -ge 1 ] || { echo "usage: exit_codes.sh <program>..." >&2; exit 2; }
for prog in "$@"; do
  check 0 "$prog" --help
  check 2 "$prog" --no-such-option
  check 2 "$prog" --help-me-not extra arguments
done
[ "$failed" -eq 0 ] || exit 1
echo "exit_codes: ok ($# programs: --help 0, bad options 2)"
