#!/usr/bin/env bash
# A stage's dynamics measured on the live loop, as a user runs it: deploy/hystloop stage on the
# two-mode example (deploy/config/two-mode: a series plant, Coleman-Hodgdon hysteresis, modes at
# 780 Hz and 2.4 kHz, 150 us of delay, 1 nm of sensor noise) starts logger, bridge and compensator,
# runs the multisine through the compensator (here shorter than the default: 3 x 4 periods of 0.1 s),
# stops them and fits the log (hystloop-identify --model stage --true-stage). Checks: the fitted
# model's modes, damping and delay are the plant's, the suggested notches sit on the modes, and the
# comparison with the plant's own stage was printed.
# Args: source dir, build dir with the programs (build/<config>), output dir.
set -euo pipefail
src="$1" bin="$2" out="$3"
rm -rf "$out"
"$src/deploy/hystloop" stage --config-dir "$src/deploy/config/two-mode" --no-build --build-dir "$bin" --rig HXG_ \
  --out "$out" --run-dir "$out/run" \
  -- --band 5:3000 --amplitude 0.5 --offset 20 --period 0.1 --periods 4 --realisations 3
report="$out/identify.txt" yaml="$out/stage/config.yaml"
fail=0
ok() { echo "ok:   $*"; }
bad() { echo "FAIL: $*"; fail=1; }
[ -f "$yaml" ] && ok "model written" || { bad "no $yaml"; exit 1; }
within() {  # what, value, truth, relative tolerance
  if awk -v v="$2" -v t="$3" -v tol="$4" 'BEGIN { d = (v - t) / t; if (d < 0) d = -d; exit !(d <= tol) }'; then
    ok "$1 = $2 (truth $3, within $4)"
  else
    bad "$1 = $2, truth $3: more than $4 off"
  fi
}
# "  pole 779.975 Hz, damping 0.03002": the two modes, in order of frequency.
mapfile -t poles < <(sed -n 's/^  pole \([0-9.e+-]*\) Hz, damping \([0-9.e+-]*\)$/\1 \2/p' "$report" | sort -g)
[ "${#poles[@]}" -eq 2 ] && ok "two modes" || bad "expected two modes, got ${#poles[@]}: ${poles[*]:-none}"
if [ "${#poles[@]}" -ge 2 ]; then
  read -r f1 z1 <<<"${poles[0]}"
  read -r f2 z2 <<<"${poles[1]}"
  within "first mode [Hz]" "$f1" 780 0.01
  within "its damping" "$z1" 0.03 0.2
  within "second mode [Hz]" "$f2" 2400 0.01
  within "its damping" "$z2" 0.02 0.3
fi
delay="$(awk '$1 == "delay_s:" {print $2; exit}' "$yaml")"
within "delay [s]" "${delay:-0}" 150e-6 0.05
notch="$(sed -n 's/^servo notch 1: \([0-9.e+-]*\) Hz.*/\1/p' "$report")"
within "first notch [Hz]" "${notch:-0}" 780 0.01
grep -q "^against the true stage (plant.stage of .*two-mode/bridge.yaml), up to 3000 Hz: model within" "$report" \
  && ok "$(grep '^against the true stage' "$report")" || bad "no comparison with the plant's stage"
exit "$fail"
