#!/usr/bin/env bash
# hystloop-bridge's command line: --help, and a bad configuration value exits 2 naming the field.
#   bridge_cli.sh <hystloop-bridge> <hystloop-compensator> <loop_probe>
source "$(dirname "$0")/loop_common.sh" "$@"
expect_help "$bridge" --config --set --lcm-url --rig --backend --noise-rms-m --drift --seconds --auto-arm
refused() { expect_refused "$bridge" "$@"; }  # expected-text args...
refused "actuator.watchdog_s" --set actuator.watchdog_s=-1
refused "actuator.u_max_V: must be greater than actuator.u_min_V" --set actuator.u_max_V=-300
refused "actuator.safe_u_V" --set actuator.safe_u_V=400
refused "bridge.backend" --backend hardware
refused "bridge.noise_rms_m" --noise-rms-m 1
refused "bridge.drift_fraction" --drift 5
refused "banning.hysteresis.b" --set banning.hysteresis.b=1e-8
refused "ro.c3" --set ro.c3=0
refused "rt.io_priority" --set rt.priority=50 --set rt.io_priority=60
refused "servo.ki" --set servo.ki=-600
refused "bridge.block_ticks" --set bridge.block_ticks=0
refused "rt.ticks_per_wake" --set bridge.block_ticks=5 --set rt.ticks_per_wake=10
refused "did you mean 'actuator.watchdog_s'" --set actuator.watchdog=0.1
printf 'actuator:\n  slew_V_per_s: -5\n' >"$dir/bad.yaml"
refused "bad.yaml: actuator.slew_V_per_s" --config "$dir/bad.yaml"
printf '# nothing yet\n' >"$dir/empty.yaml"
refused "empty.yaml: no keys in it" --config "$dir/empty.yaml"
refused "bridge.max_lead_s" --set bridge.max_lead_s=2
refused "servo.kp" --set servo.kp=1e300
# Without a key and without the keyless choice a service does not start (this test's namespace
# chose keyless for it: HYSTLOOP_AUTH_KEYLESS=1 from tools/netns-run --keyless).
HYSTLOOP_AUTH_KEYLESS=0 refused "auth.key_file: no rig key" --config "$config/bridge.yaml" --seconds 0.1
# A URL whose packets could leave the host is refused before LCM starts (this script runs inside
# tools/netns-run: even if it were not, nothing could leave the private namespace).
refused "lcm.url" --lcm-url "udpm://239.255.76.67:7667?ttl=1"
# The default configuration is valid: a short run on the in-process provider.
"$bridge" --config "$config/bridge.yaml" --lcm-url memq:// --seconds 0.2 --set rt.priority=0 --set rt.io_priority=0 \
  >"$dir/run.log" 2>&1 || fail "a run with deploy/config/bridge.yaml failed"
grep -q "summary:" "$dir/run.log" || fail "no summary at stop"
echo "bridge_cli: ok"
