# Shared by logger_record.sh, logger_rotation.sh and logger_cli.sh (sourced):
#   source logger_common.sh "$@"   (args: <hystloop-logger> <logger_probe>)
# Run inside tools/netns-run. The script's logger, started in the background, goes in $pid: the
# cleanup stops it if the script ends early (set pid="" once it has been waited for).
set -euo pipefail
logger="$1"; probe="$2"
url="udpm://239.255.76.67:7667?ttl=0"
[ "${HYSTLOOP_NETNS:-0}" = 1 ] || { echo "run me inside tools/netns-run" >&2; exit 2; }
dir="$(mktemp -d)"; pid=""
cleanup() { [ -n "$pid" ] && kill "$pid" 2>/dev/null; rm -rf "$dir"; }
trap cleanup EXIT
