#!/usr/bin/env bash
# The bridge never stops armed: with the stage held at a large voltage, (a)
# SIGTERM and (b) SHUTDOWN on HX_CONTROL each make the bridge ramp to actuator.safe_u_V before its
# real-time thread ends. Checked on the recorded HX_SENSOR samples: the last one is at the safe
# voltage (|u - safe| < 1e-9 V) with SAFE_STATE, every step within the slew limit and every step
# between SAFE_STATE samples within the ramp; the bridge exits 0 and its log and summary say how
# long the ramp took (within ceil(|u| / ramp / dt) ticks, and actuator.stop_ramp_timeout_s of
# wall time). Inside tools/netns-run.
#   bridge_safe_stop.sh <hystloop-bridge> <hystloop-compensator> <loop_probe>
source "$(dirname "$0")/loop_common.sh" "$@"
safe_V=0.0; ramp=1000; dt=1e-4  # deploy/config/bridge.yaml
# A reference held at 1.6 um: ~190 V on the simulated stage once the 0.5 s blend is over.
hold_args=(--config "$config/compensator.yaml" --set trajectory.shape=hold --set trajectory.offset_m=1.6e-6)

# True when the recorder holds 10000 samples and the last complete one is above 150 V (the last
# line may be half written).
held_high() {
  samples_recorded 10000 &&
    tail -n 2 "$dir/sensor.csv" | awk -F, 'NR == 1 { u = $3 < 0 ? -$3 : $3; high = u > 150 } END { exit !high }'
}

run_case() {  # name: sigterm | shutdown
  local name="$1"
  start_recording
  "$compensator" "${hold_args[@]}" >"$dir/compensator.log" 2>&1 & cpid=$!; pids+=($cpid)
  "$bridge" "${bridge_args[@]}" --auto-arm --summary-json "$dir/bridge_summary.json" >"$dir/bridge.log" 2>&1 &
  bpid=$!; pids+=($bpid)
  wait_log "$dir/compensator.log" "channels:"
  wait_log "$dir/bridge.log" "started in the safe state"
  # Stopped once the stage holds the large voltage (past the blend) and the recorder has the
  # second of samples the checks below want.
  wait_until 30 "$name: the stage held above 150 V with 10000 samples recorded" held_high
  if [ "$name" = sigterm ]; then
    kill -TERM $bpid  # the compensator keeps sending: the bridge must not arm again
  else
    "$probe" control --command shutdown
  fi
  for _ in $(seq 50); do kill -0 $bpid 2>/dev/null || break; sleep 0.1; done
  kill -0 $bpid 2>/dev/null && fail "$name: the bridge did not stop within 5 s"
  wait $bpid || fail "$name: the bridge exited with $?"
  kill -TERM $cpid 2>/dev/null || true
  wait $cpid || true
  wait_until 10 "$name: the recorder had the bridge's STOPPING report (sent after its last samples)" \
    stopping_reported bridge
  stop_and_analyze "$name: unsafe samples"
  [ "$(get samples)" -ge 10000 ] || fail "$name: only $(get samples) samples recorded"
  # sensor.csv: seq,utime,u_V,y_m,flags,... SAFE_STATE = 2.
  local last; last=$(tail -n 1 "$dir/sensor.csv")
  awk -F, -v safe=$safe_V '{ d = $3 - safe; if (d < 0) d = -d; exit !(d < 1e-9 && int($5 / 2) % 2 == 1) }' <<<"$last" ||
    fail "$name: the last sample is not at the safe voltage in the safe state: $last"
  local ramp_check
  ramp_check=$(awk -F, -v max=$(awk -v r=$ramp -v dt=$dt 'BEGIN { printf "%.17g", r * dt * (1 + 1e-9) + 1e-9 }') '
    NR > 1 { safe = int($5 / 2) % 2 == 1
             if (safe && prev_safe && $1 == prev_seq + 1) { d = $3 - prev_u; if (d < 0) d = -d; if (d > worst) worst = d; if (d > max) bad++ }
             prev_safe = safe; prev_seq = $1; prev_u = $3 }
    END { printf "%d %.6g", bad, worst }' "$dir/sensor.csv")
  [ "${ramp_check% *}" -eq 0 ] || fail "$name: ${ramp_check% *} safe-state steps above the ramp (worst ${ramp_check#* } V)"
  # How long the ramp took: the bridge's log and its summary.
  grep -q "safe state reached: ramped from" "$dir/bridge.log" || fail "$name: the bridge's log does not say the ramp ended"
  grep -q "summary: stop: ramped from" "$dir/bridge.log" || fail "$name: the bridge's summary does not say the ramp"
  field() { jq -r ".stop.$1" "$dir/bridge_summary.json"; }
  [ "$(field safe_reached)" = true ] || fail "$name: summary says safe_reached = $(field safe_reached)"
  local u0 ticks wall timeout_s; u0=$(field u_start_V); ticks=$(field ramp_ticks); wall=$(field wall_s); timeout_s=$(field bound_s)
  [ "$timeout_s" = 0.75 ] || fail "$name: the stop's bound is $timeout_s s, expected 0.75 s (0.25 s ramp + 0.5 s)"
  awk -v u=$u0 'BEGIN { exit !(u > 100 || u < -100) }' || fail "$name: stopped from $u0 V, not a large voltage"
  local bound; bound=$(awk -v u=$u0 -v s=$safe_V -v r=$ramp -v dt=$dt 'BEGIN { d = u - s; if (d < 0) d = -d; x = d / (r * dt); b = int(x); if (b < x) b++; print b }')
  [ "$ticks" -le "$bound" ] || fail "$name: the ramp from $u0 V took $ticks ticks, more than $bound"
  awk -v w=$wall -v t=$timeout_s 'BEGIN { exit !(w <= t) }' || fail "$name: the ramp took $wall s of wall time (bound $timeout_s s)"
  grep -q '^process=bridge \(.* \)\?state=4 ' "$dir/status.log" || fail "$name: no STOPPING report"
  echo "$name: ramped from $u0 V to $safe_V V in $ticks ticks (bound $bound), $wall s wall (bound $timeout_s s);" \
       "$(get samples) samples, max step $(get max_step_V) V, safe-state max step ${ramp_check#* } V"
  mkdir "$dir/$name"
  mv "$dir"/*.csv "$dir"/*.log "$dir"/*.txt "$dir"/*.json "$dir/$name"/
  rm -f "$dir/recording"
}

run_case sigterm
run_case shutdown
echo "bridge_safe_stop: ok"
