#!/usr/bin/env bash
# hystloop-compensator's command line: --help, a bad configuration value exits 2 naming the field,
# and a parameter snippet as hystloop-identify --out writes it is accepted (--params).
#   compensator_cli.sh <hystloop-bridge> <hystloop-compensator> <loop_probe>
source "$(dirname "$0")/loop_common.sh" "$@"
expect_help "$compensator" --config --set --lcm-url --rig --params --mode --seconds
refused() { expect_refused "$compensator" "$@"; }  # expected-text args...
refused "mem.c3" --set mem.c3=-1
refused "mem.c1" --set mem.c1=abc
refused "compensator.mode" --mode experiment
refused "compensator.mode" --mode prandtl
refused "compensator.horizon_s" --set compensator.horizon_s=0
refused "compensator.horizon_s" --set compensator.horizon_s=5
refused "replaced by compensator.horizon_s" --set compensator.lead_ticks=2
refused "the servo runs in the bridge now" --set feedback.ki=600
refused "linear.gain" --set linear.gain=0
refused "pi.weights" --set "pi.thresholds=[0, 10]" --set "pi.weights=[1e-9]"
refused "katalenic.k1" --set katalenic.k1=-40
refused "trajectory.shape" --set trajectory.shape=square
refused "did you mean 'compensator.horizon_s'" --set compensator.horizon=0.1
printf 'mem:\n  c1: -5e-9\n' >"$dir/bad_params.yaml"
refused "mem.c1" --params "$dir/bad_params.yaml"

# hystloop-identify's snippets (tools/identify, common/ident/params_yaml.cpp) load as they are.
cat >"$dir/mem.yaml" <<'YAML'
# written by hystloop-identify
mem:
  c1: 5.3e-09  # [m/V]
  c2: 2.1000000000000001e-12  # [m/V^(1+c3)]
  c3: 1.1499999999999999
YAML
cat >"$dir/pi.yaml" <<'YAML'
pi:
  count: 3
  thresholds: [0, 80, 160]  # [V]
  weights: [5e-09, 1e-09, 5e-10]  # [m/V]
linear:
  gain: 6.3e-09  # [m/V]
  offset: 1e-09  # [m]
katalenic:
  k1: 35
  k2: 0.012
  k2_slope: 0
  initial_offset: 0
  input_shaping: {kind: linear, gain: 1, offset: 0}
  output_shaping: {kind: polynomial, coefficients: [0, 3.8e-09, 0, 1e-16], domain_min: -300, domain_max: 300}
YAML
"$compensator" --config "$config/compensator.yaml" --params "$dir/mem.yaml" --params "$dir/pi.yaml" \
  --lcm-url memq:// --seconds 0.1 --set rt.priority=0 >"$dir/run.log" 2>&1 || fail "the identify snippets were refused"
grep -q "mem: c1 5.3e-09 m/V, c2 2.1e-12 m/V^(1+c3), c3 1.15" "$dir/run.log" || fail "the MEM snippet was not applied"
grep -q "pi: 3 plays up to 160 V" "$dir/run.log" || fail "the PI snippet was not applied"
grep -q "summary:" "$dir/run.log" || fail "no summary at stop"
echo "compensator_cli: ok"
