# bench/lib/banning.sh: section 5 of bench/run-all, the table of Banning's identified parameters.
# shellcheck shell=bash disable=SC2154  # $here, $build, $me ... are the sourcing script's
# banning_table W: W/banning.yaml (hystloop-identify --out) beside the simulated stage's
# deploy/config/bridge.yaml, and the log/fit lines of W/identify.txt.
banning_table() {
  local w="$1" truth="$here/deploy/config/bridge.yaml" k key unit t g
  echo "| parameter | simulated stage (Tables 1–2) | identified on the live loop | error |"
  echo "| --- | --- | --- | --- |"
  for k in a:hysteresis:m/V b:hysteresis:m/V alpha:hysteresis:1/V k:stage:1/s² c:stage:1/s; do
    IFS=: read -r key sect unit <<<"$k"
    t="$(yaml_get "$truth" "banning.$sect.$key" --default "")" || die "$truth: banning.$sect.$key"
    g="$(yaml_get "$w/banning.yaml" "banning.$sect.$key" --default "")" || die "$w/banning.yaml: banning.$sect.$key"
    awk -v k="$key" -v u="$unit" -v t="$t" -v g="$g" 'BEGIN {
      err = (t != "" && t != 0 && g != "") ? sprintf("%+.2f %%", 100 * (g - t) / t) : "n/a"
      printf "| %s [%s] | %.4g | %s | %s |\n", k, u, t, g == "" ? "n/a" : sprintf("%.6g", g), err }'
  done
  echo
  sed -n 's/^\(log:\|fit:\|lag:\)/- &/p' "$w/identify.txt"
}
