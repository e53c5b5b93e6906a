# bench/lib/gbench.sh: a Google Benchmark JSON file (--benchmark_out_format=json) as a Markdown table.
# shellcheck shell=bash disable=SC2154  # $here, $build, $me ... are the sourcing script's
# jq picks the fields, awk formats the numbers (>= 100: no decimals, >= 10: one, else two).
bench_table() {  # json -> markdown table
  echo "| benchmark | time / iteration | CPU / iteration | iterations | p50 | p99 | p99.9 | max | other |"
  echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
  jq -r '
    ["name", "family_index", "per_family_instance_index", "run_name", "run_type", "repetitions",
     "repetition_index", "threads", "iterations", "real_time", "cpu_time", "time_unit", "label",
     "error_occurred", "error_message", "aggregate_name", "aggregate_unit",
     "p50_ns", "p99_ns", "p999_ns", "max_ns"] as $skip
    | .benchmarks[] | select((.run_type // "iteration") == "iteration")
    | [.name, .time_unit, .real_time, .cpu_time, .iterations,
       (.p50_ns // ""), (.p99_ns // ""), (.p999_ns // ""), (.max_ns // ""),
       ([to_entries[] | select((.key | IN($skip[]) | not) and (.value | type) == "number")
         | "\(.key) \(.value)"] | join(";"))]
    | @tsv' "$1" |
  awk -F'\t' '
    function f(v) { return v >= 100 ? sprintf("%.0f", v) : v >= 10 ? sprintf("%.1f", v) : sprintf("%.2f", v) }
    function ns(v) { return v == "" ? "" : f(v) " ns" }
    {
      n = split($10, kv, ";"); other = ""
      for (i = 1; i <= n; i++) { split(kv[i], p, " "); other = other (i > 1 ? ", " : "") p[1] " " sprintf("%.4g", p[2]) }
      printf "| %s | %s %s | %s %s | %s | %s | %s | %s | %s | %s |\n", $1, f($3), $2, f($4), $2, $5, ns($6), ns($7), ns($8), ns($9), other
    }'
}
