# bench/lib/loop.sh: section 4 of bench/run-all, the four services for $loop_seconds.
# shellcheck shell=bash disable=SC2154  # $here, $build, $me ... are the sourcing script's
#
# loop_inside W: run inside the private namespace (tools/netns-run): start the services with the
# product's configs, arm, track the MEM paper's reference, then record in W: bridge.json (the
# bridge's --summary-json), status.txt (hystloop-ctl status --counters), usage.txt (CPU ticks, clock
# ticks per second and peak memory of each process), compensator.json (its --summary-json), the
# services' logs and the LCM log in W/log.
loop_inside() {
  local w="$1" url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304" cfg="$here/deploy/config" name
  ctl() { "$(prog hystloop-ctl)" --lcm-url "$url" "$@"; }
  declare -gA pid
  start() {  # name, args...
    local name="$1"; shift
    "$(prog "hystloop-$name")" --lcm-url "$url" "$@" >"$w/$name.log" 2>&1 &
    pid[$name]=$!
  }
  trap 'for p in "${pid[@]}"; do kill -KILL "$p" 2>/dev/null || true; done' EXIT
  start logger --out-dir "$w/log"
  # The product's configs as shipped: the 2 ms watchdog, no re-arm after a trip.
  start bridge --config "$cfg/bridge.yaml" --summary-json "$w/bridge.json"
  start compensator --config "$cfg/compensator.yaml" --summary-json "$w/compensator.json"
  start reidentifier --config "$cfg/reidentifier.yaml"
  ctl status --wait-healthy logger bridge compensator reidentifier --accept-safe bridge --accept-degraded --timeout 15 \
    >"$w/ready.txt" 2>&1 \
    || { cat "$w/ready.txt" >&2; die "the services did not become healthy (logs in $w)"; }
  ctl arm >/dev/null
  ctl trajectory --mem-paper --blend 0.5 >/dev/null
  sleep "$loop_seconds"
  ctl status --counters >"$w/status.txt" 2>&1 || true
  for name in "${!pid[@]}"; do echo "$name $(proc_usage "${pid[$name]}")" >>"$w/usage.txt"; done
  for name in reidentifier compensator bridge logger; do
    kill -TERM "${pid[$name]}" 2>/dev/null || true
    wait "${pid[$name]}" || true
  done
  trap - EXIT
}

# loop_table W: the figures of the run in W as Markdown: hystloop-report's summary.json (W/report),
# the bridge's and the compensator's --summary-json and usage.txt.
loop_table() {
  local w="$1"
  echo "| figure | value | source |"
  echo "| --- | --- | --- |"
  # %g-style formatting of the report's figures is left to awk (jq has no printf).
  jq -r --slurpfile b "$w/bridge.json" '
    def n: if . == null then "n/a" else tostring end;
    $b[0] as $b
    | "| late ticks (the buffer had no command: the last feedforward held) | \(.late_tick_fraction | if . == null then "n/a" else . * 100 end | tostring) % of \(.armed_samples | n) armed ticks (\(.late_samples | n)) | hystloop-report (HX_SENSOR flags) |",
      "| watchdog trips (2 ms) | \(.watchdog_trips | n) | hystloop-report (\(.watchdog_trips_source | n)) |",
      "| lowest buffer depth at an armed tick | \($b.buffer_min_depth_ticks) ticks (horizon 500) | the bridge'"'"'s --summary-json |",
      "| run-ahead of the command blocks min / p1 / p50 | \(.run_ahead_min_ticks | n) / \(.run_ahead_p01_ticks | n) / \(.run_ahead_p50_ticks | n) ticks | hystloop-report (block seq − sample_seq) |",
      "| sensor block → its answer back at the bridge p50 / p99 / max | \($b.block_to_answer_us.p50) / \($b.block_to_answer_us.p99) / \($b.block_to_answer_us.max) µs | the bridge'"'"'s --summary-json |",
      "| commands rejected by the bridge | \(.commands_rejected | n) | hystloop-report (\(.commands_rejected_source | n)) |",
      "| missing sample ticks | \(.missing_samples | n) | hystloop-report |",
      "| logger gaps | \(.logger_gaps | n) | hystloop-report (\(.logger_gaps_source | n)) |",
      "| parameter sets swapped in by the re-identifier | \(.params_updates | n) | hystloop-report |",
      "| tracking RMS error (measured position, default configs) | \(.rms_error_m | if . == null then "n/a" else . * 1e9 end | tostring) nm overall, \(.rms_error_last_5s_m | if . == null then "n/a" else . * 1e9 end | tostring) nm in the last 5 s | hystloop-report |",
      "| messages per second | \(.messages_per_s // {} | to_entries | sort_by(.key) | map("\(.key) \(.value | round)") | join(", ")) | hystloop-report |"
  ' "$w/report/summary.json" | round_figures
  stop_summaries "$w"
  echo
  echo "CPU and peak memory per process over the run:"
  echo
  echo "| process | CPU (of one core) | peak resident memory |"
  echo "| --- | --- | --- |"
  sort "$w/usage.txt" | awk -v s="$loop_seconds" '
    { cpu = 100 * $2 / $3 / s; total += cpu; printf "| %s | %.1f %% | %.1f MiB |\n", $1, cpu, $4 / 1024 }
    END { printf "| all four | %.1f %% | |\n", total }'
}

# The late fraction to 3 and the RMS errors to 4 significant digits (as the document shows them).
round_figures() {
  awk -F' \\| ' 'BEGIN { OFS = " | " }
    $1 ~ /late ticks/ && $2 ~ /^[-0-9.e+]+ %/ { split($2, a, " "); $2 = sprintf("%.3g", a[1]) substr($2, length(a[1]) + 1) }
    $1 ~ /RMS error/ {
      n = split($2, a, " "); s = ""
      for (i = 1; i <= n; i++) s = s (i > 1 ? " " : "") ((a[i] ~ /^[-0-9.]+(e[-+][0-9]+)?$/ && i < n && a[i + 1] == "nm") ? sprintf("%.4g", a[i]) : a[i])
      $2 = s }
    { print }'
}

# The services' stop summaries, from their --summary-json (the same figures as their "summary:" log lines).
stop_summaries() {
  jq -r '[.ticks, .ticks_skipped, .ticks_caught_up, .applied, .late_ticks, .late_tick_fraction, .stale, .duplicates,
          .clamped, .slew_limited, .watchdog_trips, .rejected_nonfinite, .rejected_future, .buffer_min_depth_ticks,
          .block_to_answer_us.p50, .block_to_answer_us.p99, .block_to_answer_us.max, .block_to_answer_us.count,
          .sensor_blocks, .command_blocks, .command_blocks_rejected, .samples_dropped,
          .stop.safe_reached, .stop.u_start_V, .stop.safe_u_V, .stop.ramp_ticks, .stop.ramp_s, .stop.wall_s, .stop.bound_s]
         | @tsv' "$1/bridge.json" |
  awk -F'\t' '{
    s = "| bridge: summary | "; e = " | the bridge'"'"'s --summary-json |\n"
    printf s "%s ticks (%s skipped, %s run late to catch up), %s commands applied, %s late (%.3g %% of armed ticks), %s stale, %s duplicate, %s clamped, %s slew-limited, %s watchdog trips, %s non-finite and %s too-far-ahead rejected; lowest buffer depth %s ticks" e,
      $1, $2, $3, $4, $5, 100 * $6, $7, $8, $9, $10, $11, $12, $13, $14
    if ($18 > 0) printf "| bridge: sensor block sent -> its answer received | p50 %.1f us, p99 %.1f us, max %.1f us over %s commands" e, $15, $16, $17, $18
    printf s "%s sensor blocks published, %s command blocks received (%s rejected), %s dropped samples" e, $19, $20, $21, $22
    printf s "stop: %s from %.6g V to the safe %s V in %s ticks (%.4g s loop time, %.4g s wall; bound %s s)" e,
      ($23 == "true" ? "ramped" : "ramp NOT finished"), $24, $25, $26, $27, $28, $29
  }'
  jq -r '[.samples, .command_ticks_published, .command_blocks_published, .ticks_behind, .gaps, .out_of_order,
          .params_accepted, .params_rejected, .params_swapped, .params_invalid,
          .block_to_answer_us.p50, .block_to_answer_us.p99, .block_to_answer_us.max, .block_to_answer_us.count] | @tsv' \
    "$1/compensator.json" |
  awk -F'\t' '{
    e = " | the compensator'"'"'s --summary-json |\n"
    printf "| compensator: summary | %s samples, %s command ticks published in %s blocks, %s ticks planned too late, %s gaps, %s out of order, params %s accepted / %s refused / %s swapped, %s invalid sets ignored" e,
      $1, $2, $3, $4, $5, $6, $7, $8, $9, $10
    if ($14 > 0) printf "| compensator: sensor block received -> its answer published | p50 %.1f us, p99 %.1f us, max %.1f us" e, $11, $12, $13
  }'
}
