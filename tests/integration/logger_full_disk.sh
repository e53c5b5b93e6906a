#!/usr/bin/env bash
# hystloop-logger on a full disk: its output folder is a 2 MB tmpfs, mounted in a
# private mount namespace, half of it taken by a ballast file, and the probe sends ~11 MB.
# The logger must keep running, say "FAULT: disk full" on HX_STATUS while it cannot write,
# count every event it could not write as dropped, resume in a new file once the ballast is
# removed (and fill the disk again), exit non-zero, and leave only files that lcm::LogFile
# reads to their end (no file cut mid-event, no empty file), holding exactly the events it
# says it wrote.
# Needs root (mount); run inside tools/netns-run.
#   logger_full_disk.sh <hystloop-logger> <logger_probe>
set -euo pipefail
logger="$1"; probe="$2"
url="udpm://239.255.76.67:7667?ttl=0"
[ "${HYSTLOOP_NETNS:-0}" = 1 ] || { echo "run me inside tools/netns-run" >&2; exit 2; }
if [ "$(id -u)" != 0 ]; then echo "SKIP: mounting a tmpfs needs root"; exit 77; fi
if [ "${HYSTLOOP_MOUNTNS:-0}" != 1 ]; then  # again, in a private mount namespace
  exec unshare -m --propagation private -- env HYSTLOOP_MOUNTNS=1 "$0" "$@"
fi
source "$(dirname "$0")/wait_common.sh"
dir="$(mktemp -d)"; pid=""; watcher=""
cleanup() {
  [ -n "$pid" ] && kill "$pid" 2>/dev/null
  [ -n "$watcher" ] && kill "$watcher" 2>/dev/null
  umount "$dir/disk" 2>/dev/null || true
  rm -rf "$dir"
}
trap cleanup EXIT
mkdir "$dir/disk"
mount -t tmpfs -o size=2m tmpfs "$dir/disk"
head -c 1000000 /dev/zero >"$dir/disk/ballast"
stream=(--blocks 8000 --block-ticks 20 --commands 8000)

"$probe" watch-status --url "$url" --seconds 30 >"$dir/status.jsonl" &
watcher=$!
"$logger" --lcm-url "$url" --out-dir "$dir/disk/logs" --max-file-mb 0.3 --summary "$dir/summary.json" \
  --log-level warn 2>"$dir/logger.err" &
pid=$!
"$probe" publish --url "$url" "${stream[@]}" --rate-hz 2000 &
publisher=$!
wait_until 30 "the logger reported FAULT: disk full on HX_STATUS" file_has "$dir/status.jsonl" '"FAULT: disk full'
rm "$dir/disk/ballast"  # space again: the logger resumes at its next retry
wait "$publisher"
# Still running once it has handled the whole stream: it answers a request sent after it.
if ! "$probe" sync --url "$url" --wait-logger-s 20; then
  kill -0 "$pid" 2>/dev/null && { echo "the logger runs but did not answer after the stream" >&2; exit 1; }
fi
kill -0 "$pid" || { echo "the logger did not keep running on a full disk" >&2; cat "$dir/logger.err" >&2; exit 1; }
kill -TERM "$pid"; rc=0; wait "$pid" || rc=$?; pid=""
kill "$watcher" 2>/dev/null || true; wait "$watcher" 2>/dev/null || true; watcher=""
echo "logger exited $rc; df: $(df -k --output=used,size "$dir/disk" | tail -1)"
[ "$rc" != 0 ] || { echo "the logger lost events to a full disk and exited 0" >&2; exit 1; }
cat "$dir/logger.err"
grep -q "disk fault: disk full" "$dir/logger.err" || { echo "no disk fault in the log:" >&2; cat "$dir/logger.err" >&2; exit 1; }

echo "== HX_STATUS said so"
jq -se '
  any(.[]; .state == 2 and (.detail | startswith("FAULT: disk full (write: No space left on device)"))) and
  (last | .counters.dropped > 0 and .counters.disk_errors > 0 and .counters.disk_events_lost > 0)
' "$dir/status.jsonl" >/dev/null || { echo "status did not report the fault:" >&2; tail -3 "$dir/status.jsonl" >&2; exit 1; }
grep -m1 '"FAULT' "$dir/status.jsonl" | jq -r .detail
grep -m1 '"recovered' "$dir/status.jsonl" | jq -r .detail || echo "(no report caught the short recovery)"

echo "== the summary counts it"
jq -e '
  .disk.ok == false and .disk.errors > 0 and .disk.events_lost > 0 and .disk.recoveries >= 1 and
  .dropped.write_failed == .disk.events_lost and .totals.dropped >= .disk.events_lost and
  ([.files[].events] | add) == .totals.written and .totals.written + .totals.dropped == .totals.received
' "$dir/summary.json" >/dev/null || { echo "summary not as expected:" >&2; cat "$dir/summary.json" >&2; exit 1; }
jq -c '{written: .totals.written, dropped: .totals.dropped, disk: .disk, files: (.files | length)}' "$dir/summary.json"

echo "== every file on the disk reads to its end, with exactly the events the logger wrote"
mapfile -t files < <(ls "$dir"/disk/logs/*.lcmlog | sort)
[ "$(ls "$dir"/disk/logs | grep -vc '\.lcmlog$' || true)" = 0 ] || { echo "stray files:" >&2; ls -la "$dir/disk/logs" >&2; exit 1; }
listed=$(jq -r '.files[].path' "$dir/summary.json" | sort)
[ "$listed" = "$(printf '%s\n' "${files[@]}")" ] || { echo "files on disk differ from the summary's" >&2; exit 1; }
read_back=$("$probe" read-logs "${files[@]}")
echo "$read_back"
written=$(jq -r .totals.written "$dir/summary.json")
[ "$(jq -r .events <<<"$read_back")" = "$written" ] || { echo "read $read_back, the logger says $written" >&2; exit 1; }
lcm-logplayer --lcm-url="udpm://239.255.76.67:7668?ttl=0" --speed=1000 "${files[0]}"
echo "ok"
