#!/usr/bin/env bash
# A raster line on the live loop with learning (deploy/hystloop scan, shortened): bridge and
# compensator with the product's configs (deploy/config: PI-15, the stage's inverse, learning on,
# the servo's defaults), a 1 um triangle at 50 Hz sent with hystloop-ctl, learned for ~5 s
# (250 periods). Checks: the compensator takes the trajectory (ctl exit 0), no tick late, none
# clamped (range or slew), learning_periods grows, and the RMS of y_ref - y (measured, with the
# 1 nm RMS sensor noise) over the last second is below SCAN_RMS_BOUND_M; against the simulator's
# true position (HX_SIM_TRUTH) the same RMS below SCAN_TRUE_RMS_BOUND_M and the max below
# SCAN_TRUE_MAX_BOUND_M, with every tick's truth received. Prints what it measured.
# Inside tools/netns-run.
#   scan_learning.sh <hystloop-bridge> <hystloop-compensator> <loop_probe> <hystloop-ctl>
source "$(dirname "$0")/loop_common.sh" "$@"
ctl="$4"
# Measured on this 2-core VM beside builds: 1.28-1.29 nm over the last second (5 runs), 1.5 nm in
# deploy/hystloop scan (whose re-identifier swaps refits in); the sensor noise alone is 1 nm. The
# bound is the product's goal against the measured position, 1.5 x what was measured.
rms_bound_m="${SCAN_RMS_BOUND_M:-2.0e-9}"
# The product's targets against the true position, with learning: RMS <= 1 nm, max <= 5 nm.
true_rms_bound_m="${SCAN_TRUE_RMS_BOUND_M:-1.0e-9}"
true_max_bound_m="${SCAN_TRUE_MAX_BOUND_M:-5.0e-9}"
learn_periods=250  # 5 s at 50 Hz

start_recording
"$compensator" --config "$config/compensator.yaml" >"$dir/compensator.log" 2>&1 & cpid=$!; pids+=($cpid)
"$bridge" "${bridge_args[@]}" --auto-arm >"$dir/bridge.log" 2>&1 & bpid=$!; pids+=($bpid)
wait_log "$dir/compensator.log" "channels:"
wait_log "$dir/bridge.log" "started in the safe state"
"$ctl" status --wait-healthy bridge compensator --timeout 20 >"$dir/ctl-status.out" 2>&1 ||
  fail "bridge and compensator not healthy: $(cat "$dir/ctl-status.out")"

"$ctl" trajectory --shape triangle --amplitude 1e-6 --frequency 50 --blend 0.3 >"$dir/ctl-trajectory.out" 2>&1 ||
  fail "the compensator did not take the 50 Hz triangle (hystloop-ctl exit $?): $(cat "$dir/ctl-trajectory.out")"
grep "accepted\|shaped" "$dir/ctl-trajectory.out"

# Learning from its first periods on: wait until it has learned some, then until it has learned
# learn_periods (the compensator reports once a second).
wait_until 30 "the compensator learned a period (learning_periods >= 10)" \
  status_at_least compensator learning_periods 10
first="$(status_key compensator learning_periods)"
wait_until 30 "the compensator learned $learn_periods periods (from $first)" \
  status_at_least compensator learning_periods "$learn_periods"
last="$(status_key compensator learning_periods)"
[ "$last" -gt "$first" ] || fail "learning_periods did not grow ($first -> $last)"
expect_value compensator learning_active 1

"$probe" control --command shutdown
expect_shutdown 100 $bpid $cpid
stop_recording

# The recorded ticks: flags bit 2 SAFE_STATE, 16 LATE_COMMAND, 1 SATURATED | 8 SLEW_LIMITED. The
# last second: the 10000 newest armed ticks with a reference (the shutdown's ramp left out).
# The true position of each tick from truth.csv (seq,y_true_m), joined by seq.
read -r armed late clamped n rms max n_true rms_true max_true <<<"$(awk -F, '
  function bit(v, b) { return int(v / b) % 2 }
  FNR == 1 { next }
  FILENAME ~ /truth.csv$/ { truth[$1] = $2; next }
  { safe = bit($5, 2); if (!safe) { armed++; late += bit($5, 16); clamped += (bit($5, 1) || bit($5, 8)) } }
  !safe && $6 != "nan" && $6 != "-nan" { e[++k] = $6 - $4; r[k] = $6; q[k] = $1 }
  END {
    from = k > 10000 ? k - 10000 + 1 : 1
    for (i = from; i <= k; i++) {
      s += e[i] * e[i]; a = e[i] < 0 ? -e[i] : e[i]; if (a > m) m = a
      if (q[i] in truth) { nt++; d = r[i] - truth[q[i]]; st += d * d; d = d < 0 ? -d : d; if (d > mt) mt = d }
    }
    n = k - from + 1
    printf "%d %d %d %d %.4g %.4g %d %.4g %.4g\n", armed, late, clamped, n, sqrt(s / n), m, nt, nt ? sqrt(st / nt) : 0, mt
  }' "$dir/truth.csv" "$dir/sensor.csv")"
echo "scan_learning: armed ticks $armed, late $late, clamped $clamped; learning_periods $first -> $last;" \
  "last second ($n ticks): RMS $(awk -v v="$rms" 'BEGIN { printf "%.2f", v * 1e9 }') nm," \
  "max $(awk -v v="$max" 'BEGIN { printf "%.2f", v * 1e9 }') nm (bound $rms_bound_m m);" \
  "against the true position ($n_true ticks): RMS $(awk -v v="$rms_true" 'BEGIN { printf "%.2f", v * 1e9 }') nm," \
  "max $(awk -v v="$max_true" 'BEGIN { printf "%.2f", v * 1e9 }') nm (bounds $true_rms_bound_m, $true_max_bound_m m)"
[ "$armed" -gt 50000 ] || fail "only $armed armed ticks recorded"
[ "$late" = 0 ] || fail "$late ticks were late"
[ "$clamped" = 0 ] || fail "$clamped ticks were clamped (range or slew)"
[ "$n" = 10000 ] || fail "only $n ticks with a reference in the last second"
awk -v r="$rms" -v b="$rms_bound_m" 'BEGIN { exit !(r < b) }' || fail "RMS $rms m over the last second, bound $rms_bound_m m"
[ "$n_true" = "$n" ] || fail "the true position of only $n_true of the last $n ticks arrived on HX_SIM_TRUTH"
awk -v r="$rms_true" -v b="$true_rms_bound_m" 'BEGIN { exit !(r < b) }' ||
  fail "RMS $rms_true m against the true position over the last second, bound $true_rms_bound_m m"
awk -v r="$max_true" -v b="$true_max_bound_m" 'BEGIN { exit !(r < b) }' ||
  fail "max $max_true m against the true position over the last second, bound $true_max_bound_m m"
expect_value bridge late 0
expect_value bridge watchdog_trips 0
# The plan's own clamps (the feedforward held inside the range / the plan's share of the slew
# limit before it is sent) are printed, not failed on: with learning on, the correction at the
# corners of this line asked for more than the share on 2 ticks in 1 of 5 runs, which the bridge
# then applied unclamped (clamped above counts what the actuator got).
echo "scan_learning: the compensator's plan clamped $(value compensator u_clamped) ticks to the range," \
  "$(value compensator u_slew_clamped) to the slew limit's share"
echo "scan_learning: ok"
