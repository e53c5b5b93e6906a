# Bounded waits on a condition instead of fixed sleeps, for every integration script (sourced;
# loop_common.sh sources it too). A fixed sleep that stands for a condition is too long on a quiet
# machine and too short on a busy one; a wait ends when the condition holds and, past its
# deadline, fails the test naming what did not happen.
#
# wait_until polls a command every 0.05 s until it succeeds; after TIMEOUT_S (whole seconds; be
# generous: sanitizer builds and loaded hosts are slow) it fails through the script's failure
# function (wait_fail, default `fail`, when the script defines one; else it prints and exits 1).
wait_until() {  # timeout_s description command...
  local timeout_s="$1" what="$2"; shift 2
  local deadline=$(( ${EPOCHREALTIME/./} + timeout_s * 1000000 ))
  until "$@"; do
    if [ "${EPOCHREALTIME/./}" -ge "$deadline" ]; then
      local msg="timed out after ${timeout_s} s waiting until $what"
      if declare -F "${wait_fail:-fail}" >/dev/null; then "${wait_fail:-fail}" "$msg"; fi
      echo "FAIL: $msg" >&2
      exit 1
    fi
    sleep 0.05
  done
}
# True when a file holds a fixed text (read directly: grep -q in a pipe under pipefail can fail
# on SIGPIPE).
file_has() { grep -qF -- "$2" "$1" 2>/dev/null; }  # file text
