#!/usr/bin/env bash
# Sample -> command round trips between two processes over udpm at 10 kHz; prints the
# round-trip percentiles and fails if any sample goes unanswered. Run inside tools/netns-run.
#   lcm_udpm_round_trip.sh <lcm_probe> [rounds] [rate_hz]
set -euo pipefail
probe="$1"; rounds="${2:-5000}"; rate="${3:-10000}"
url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"  # 10 kHz survives a busy CPU (see url.hpp)
[ "${HYSTLOOP_NETNS:-0}" = 1 ] || { echo "run me inside tools/netns-run" >&2; exit 2; }
dir="$(mktemp -d)"; trap 'rm -rf "$dir"' EXIT
"$probe" echo --url "$url" --prefix HX_ --rounds "$rounds" --timeout-s 8 --ready-file "$dir/ready" &
echo_pid=$!
for _ in $(seq 100); do [ -e "$dir/ready" ] && break; sleep 0.05; done
"$probe" ping --url "$url" --prefix HX_ --rounds "$rounds" --rate-hz "$rate"
wait "$echo_pid"
