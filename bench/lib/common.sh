# bench/lib/common.sh: helpers of bench/run-all and bench/loop-timing (sourced; needs $here, $build, $me).
# shellcheck shell=bash disable=SC2154  # $here, $build, $me ... are the sourcing script's
say() { printf '%s: %s\n' "${me##*/}" "$*" >&2; }
die() { say "$*"; exit 1; }
prog() {  # path of a built program
  local p; p="$(find "$build/bench" "$build/services" "$build/tools" -maxdepth 2 -type f -name "$1" -perm -u+x 2>/dev/null | head -n 1)"
  [ -n "$p" ] || die "$1 is not built in $build"
  echo "$p"
}
rel() { echo "${1#"$here"/}"; }  # a path as the document shows it
# A value of a YAML file (hystloop-ctl config-get, as deploy/hystloop reads YAML).
yaml_get() { "$(prog hystloop-ctl)" config-get "$@"; }
# CPU time (utime + stime, clock ticks), clock ticks per second and peak resident memory [kB] of a pid.
proc_usage() {
  local st; read -r -a st < <(sed 's/^.*) //' "/proc/$1/stat")
  echo "$(( st[11] + st[12] )) $(getconf CLK_TCK) $(awk '/VmHWM/ {print $2}' "/proc/$1/status")"
}
