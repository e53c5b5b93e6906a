#!/usr/bin/env bash
# Two processes exchange every message type over real udpm LCM (ttl=0). Run inside
# tools/netns-run: the multicast never leaves the private namespace.
#   lcm_udpm_exchange.sh <lcm_probe> [rounds]
source "$(dirname "$0")/lcm_common.sh" "$@"
rounds="${2:-400}"

start_peer subscribe --url "$url" --prefix HX_ --rounds "$rounds" --timeout-s 8
"$probe" publish --url "$url" --prefix HX_ --rounds "$rounds" --rate-hz 2000
wait "$peer"
