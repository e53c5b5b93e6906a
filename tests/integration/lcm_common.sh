# Shared by the lcm_*.sh integration tests (sourced): source lcm_common.sh "$@"
# (args: <lcm_probe> ...). Run inside tools/netns-run: the multicast never leaves the private
# namespace. Background processes go in pids: the cleanup stops those still running.
set -euo pipefail
probe="$1"
url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"  # 10 kHz survives a busy CPU (see url.hpp)
[ "${HYSTLOOP_NETNS:-0}" = 1 ] || { echo "run me inside tools/netns-run" >&2; exit 2; }
source "$(dirname "${BASH_SOURCE[0]}")/wait_common.sh"
dir="$(mktemp -d)"; pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  rm -rf "$dir"
}
trap cleanup EXIT
# Starts `lcm_probe MODE args... --ready-file F` in the background (its pid in peer) and waits until
# it has subscribed, when it writes F.
start_peer() {  # mode args...
  rm -f "$dir/ready"
  "$probe" "$@" --ready-file "$dir/ready" &
  peer=$!; pids+=("$peer")
  wait_until 5 "lcm_probe $1 became ready" test -e "$dir/ready"
}
