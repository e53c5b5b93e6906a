#!/usr/bin/env bash
# hystloop-logger's command line and control: --help works; a bad value exits 2 naming
# the field (also a --channels regex LCM cannot compile, and a --summary that is a directory,
# both before anything is created); an unknown logger.* key in the configuration file exits 2 with a suggestion;
# a control_t SHUTDOWN addressed to "logger" stops it cleanly with a summary.
# Run inside tools/netns-run.
#   logger_cli.sh <hystloop-logger> <logger_probe>
source "$(dirname "$0")/logger_common.sh" "$@"

expect_exit() {  # <code> <text in stderr> args...
  local code="$1" text="$2"; shift 2
  local rc=0
  "$logger" "$@" >"$dir/out" 2>"$dir/err" || rc=$?
  [ "$rc" = "$code" ] || { echo "'$*' exited $rc, expected $code" >&2; cat "$dir/err" >&2; exit 1; }
  grep -qF -- "$text" "$dir/out" "$dir/err" || { echo "'$*' did not say '$text':" >&2; cat "$dir/out" "$dir/err" >&2; exit 1; }
}

echo "== options"
expect_exit 0 "--max-file-mb" --help
expect_exit 2 "logger.max_file_mb: must be in [0, 1e+09] (got -1)" --max-file-mb=-1 --out-dir "$dir/x"
expect_exit 2 "logger.max_file_s: expected a number, got 'soon'" --max-file-s soon --out-dir "$dir/x"
expect_exit 2 "logger.queue_mb" --set logger.queue_mb=0 --out-dir "$dir/x"
expect_exit 2 "rig.prefix" --rig hx --out-dir "$dir/x"
expect_exit 2 "logger.channels: not a regular expression LCM accepts" --channels 'HX_([' --lcm-url "$url" --out-dir "$dir/x"
mkdir "$dir/sumdir"
expect_exit 2 "logger.summary: '$dir/sumdir' is a directory" --summary "$dir/sumdir" --lcm-url "$url" --out-dir "$dir/x"
[ -z "$(ls -A "$dir/sumdir")" ] || { echo "a refused --summary left files behind" >&2; ls -la "$dir/sumdir" >&2; exit 1; }
printf 'logger:\n  max_file_mbb: 5\nbridge:\n  anything: 1\n' >"$dir/bad.yaml"
expect_exit 2 "did you mean 'logger.max_file_mb'" --config "$dir/bad.yaml" --out-dir "$dir/x"
[ ! -e "$dir/x" ] || { echo "a refused configuration still created the log directory" >&2; exit 1; }

echo "== control SHUTDOWN"
printf 'logger:\n  out_dir: %s\n  file_prefix: cfg_\n' "$dir/c" >"$dir/good.yaml"
"$logger" --lcm-url "$url" --config "$dir/good.yaml" --summary "$dir/c/run.json" --log-level warn &
pid=$!
"$probe" publish --url "$url" --blocks 300 --commands 300 --rate-hz 2000
"$probe" shutdown --url "$url"
rc=0
for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
wait "$pid" || rc=$?; pid=""
[ "$rc" = 0 ] || { echo "logger exited $rc after SHUTDOWN" >&2; exit 1; }
jq -e '.stop_reason == "control SHUTDOWN" and .channels.HX_SENSOR.written == 300 and .totals.dropped == 0' \
  "$dir/c/run.json" >/dev/null || { cat "$dir/c/run.json" >&2; exit 1; }
ls "$dir"/c/cfg_hystloop-*.000.lcmlog >/dev/null
echo "ok"
