#!/usr/bin/env bash
# Two processes exchange every message type over real udpm LCM (ttl=0). Run inside
# tools/netns-run: the multicast never leaves the private namespace.
#   lcm_udpm_exchange.sh <lcm_probe> [rounds]
set -euo pipefail
probe="$1"; rounds="${2:-400}"
url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"  # 10 kHz survives a busy CPU (see url.hpp)
[ "${HYSTLOOP_NETNS:-0}" = 1 ] || { echo "run me inside tools/netns-run" >&2; exit 2; }
dir="$(mktemp -d)"; trap 'rm -rf "$dir"' EXIT

"$probe" subscribe --url "$url" --prefix HX_ --rounds "$rounds" --timeout-s 8 --ready-file "$dir/ready" &
sub=$!
for _ in $(seq 100); do [ -e "$dir/ready" ] && break; sleep 0.05; done
[ -e "$dir/ready" ] || { echo "subscriber never became ready" >&2; kill "$sub"; exit 1; }
"$probe" publish --url "$url" --prefix HX_ --rounds "$rounds" --rate-hz 2000
wait "$sub"
