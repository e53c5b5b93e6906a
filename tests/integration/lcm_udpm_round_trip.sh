#!/usr/bin/env bash
# Sample -> command round trips between two processes over udpm at 10 kHz; prints the
# round-trip percentiles and fails if any sample goes unanswered. Run inside tools/netns-run.
#   lcm_udpm_round_trip.sh <lcm_probe> [rounds] [rate_hz]
source "$(dirname "$0")/lcm_common.sh" "$@"
rounds="${2:-5000}"; rate="${3:-10000}"
start_peer echo --url "$url" --prefix HX_ --rounds "$rounds" --timeout-s 8
"$probe" ping --url "$url" --prefix HX_ --rounds "$rounds" --rate-hz "$rate"
wait "$peer"
