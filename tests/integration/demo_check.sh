#!/usr/bin/env bash
# The whole product as a user runs it: deploy/hystloop demo starts the four services (logger,
# bridge, compensator, re-identifier) as separate processes in a private network namespace,
# waits for each to report on HX_STATUS, runs the identification segment and tracking from
# deliberately wrong MEM parameters, stops them and writes the report. Then checks what the
# issue asks: every channel logged, no tick missing, no watchdog trip, (almost) no late tick, the
# re-identifier published at least one set, and the stage tracks to a few nanometres.
# Args: source dir, build dir with the programs (build/<config>), output dir.
set -euo pipefail
src="$1" bin="$2" out="$3"
rm -rf "$out"
"$src/deploy/hystloop" demo --no-build --build-dir "$bin" --rig HXT_ --seconds 12 --out "$out" \
  --run-dir "$out/run"
s="$out/summary.json"
[ -f "$s" ] || { echo "FAIL: no $s"; exit 1; }
fail=0
source "$(dirname "$0")/summary_checks.sh"
check_loop_summary "$s" HXT_
# Keyed by default: the deploy script made the rig key (0600) and every service checked with it.
key="$out/run/rig.key"
if [ -f "$key" ] && [ "$(stat -c %a "$key")" = 600 ]; then echo "ok:   rig key $key made, mode 600"
else echo "FAIL: no rig key with mode 600 at $key"; fail=1; fi
for svc in logger bridge compensator reidentifier; do
  if grep -q "signed and checked with the rig key $key" "$out/run/$svc.log"; then echo "ok:   $svc keyed"
  else echo "FAIL: $svc did not run keyed: $(grep -m1 'auth:' "$out/run/$svc.log")"; fail=1; fi
done
for f in hysteresis_u_y.png tracking_error.png; do
  [ -s "$out/$f" ] && echo "ok:   $f written" || { echo "FAIL: $f missing"; fail=1; }
done
print_loop_summary "$s"
exit "$fail"
