#!/usr/bin/env bash
# Rotation: by size (--max-file-mb 0.2, i.e. 200 kB) the recording is split into many
# files, none larger than the limit and none empty, named in order, whose union read in
# that order is the complete stream; by age (--max-file-s 0.25) a ~1.2 s recording makes
# several files too. Run inside tools/netns-run.
#   logger_rotation.sh <hystloop-logger> <logger_probe>
source "$(dirname "$0")/logger_common.sh" "$@"
stream=(--blocks 4000 --block-ticks 10 --gap-at 100 --gap-len 3 --commands 4000)

record() {  # <out dir> <rate> logger options...
  local out="$1" rate="$2"; shift 2
  "$logger" --lcm-url "$url" --out-dir "$out" --file-prefix rot_ --log-level warn "$@" &
  pid=$!
  "$probe" publish --url "$url" "${stream[@]}" --rate-hz "$rate"
  # Stopped once it has received the whole stream (it answered a request sent after it).
  "$probe" sync --url "$url" --wait-logger-s 20 || { echo "the logger did not answer after the stream" >&2; exit 1; }
  kill -TERM "$pid"; local rc=0; wait "$pid" || rc=$?; pid=""
  [ "$rc" = 0 ] || { echo "logger exited $rc" >&2; exit 1; }
}

echo "== by size"
record "$dir/size" 4000 --max-file-mb 0.2
mapfile -t files < <(ls "$dir"/size/rot_hystloop-*.lcmlog | sort)
echo "${#files[@]} files"
[ "${#files[@]}" -ge 10 ] || { echo "expected >= 10 files, got ${#files[@]}" >&2; exit 1; }
for f in "${files[@]}"; do
  size=$(stat -c %s "$f")
  [ "$size" -le 200000 ] && [ "$size" -gt 0 ] || { echo "$f has $size bytes (limit 200000)" >&2; exit 1; }
done
"$probe" check-log "${stream[@]}" "${files[@]}"
summary=$(ls "$dir"/size/rot_hystloop-*.summary.json)
jq -e --argjson n "${#files[@]}" '
  (.files | length) == $n and .totals.dropped == 0 and
  ([.files[].events] | add) == .totals.written and
  .channels.HX_SENSOR.sequence.missing == 30 and .channels.HX_SENSOR.sequence.gaps == [[1000, 1029]]
' "$summary" >/dev/null || { echo "summary not as expected:" >&2; cat "$summary" >&2; exit 1; }

echo "== by age"
record "$dir/age" 3000 --max-file-s 0.25
mapfile -t files < <(ls "$dir"/age/rot_hystloop-*.lcmlog | sort)
echo "${#files[@]} files"
[ "${#files[@]}" -ge 3 ] || { echo "expected >= 3 files, got ${#files[@]}" >&2; exit 1; }
"$probe" check-log "${stream[@]}" "${files[@]}"
echo "ok"
