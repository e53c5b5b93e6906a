# Shell helpers shared by tools/replay-check and tools/replay/make-golden (sourced; needs
# $here = the source tree, $build = an optional build tree, and a die function).

# URL of every replay process: private namespace, ttl=0, the receive buffer a 10 kHz
# subscriber needs (common/lcm/url.hpp kRecommendedRecvBufBytes).
replay_url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"

# Path of a built program: in $build, else $HYSTLOOP_BUILD_DIR(/release), build/release, build.
find_program() {
  local dirs=() d p
  if [ -n "${build:-}" ]; then dirs=("$build"); else
    [ -n "${HYSTLOOP_BUILD_DIR:-}" ] && dirs+=("$HYSTLOOP_BUILD_DIR" "$HYSTLOOP_BUILD_DIR/release")
    dirs+=("$here/build/release" "$here/build")
  fi
  for d in "${dirs[@]}"; do
    [ -d "$d" ] || continue
    p="$(find "$d/services" "$d/tools" -maxdepth 2 -type f -name "$1" -perm -u+x 2>/dev/null | head -n 1)"
    [ -n "$p" ] && { echo "$p"; return 0; }
  done
  die "$1 not found in ${dirs[*]} (build it, or pass --build DIR)"
}

# Waits up to 5 s until file $2 holds the text $3 while pid $1 lives; 0 when it does.
wait_for_line() {
  local pid="$1" file="$2" text="$3"
  for _ in $(seq 100); do
    grep -q -- "$text" "$file" 2>/dev/null && return 0
    kill -0 "$pid" 2>/dev/null || return 1
    sleep 0.05
  done
  return 1
}

# Starts hystloop-logger recording channels matching $2 into folder $1 (its own log: $1.log);
# sets recorder_pid. lcm-logger is not used: its subscription queue (LCM's default) drops
# messages at 10 kHz whenever it is descheduled for a few milliseconds on a busy machine.
start_recorder() {
  local dir="$1" channels="$2"
  mkdir -p "$dir"
  "$(find_program hystloop-logger)" --lcm-url "$replay_url" --rig "${rig:-HX_}" --out-dir "$dir" \
    --channels "$channels" --flush-interval-s 0.05 >"$dir.log" 2>&1 &
  recorder_pid=$!
  wait_for_line "$recorder_pid" "$dir.log" "recording '" || { tail -n 20 "$dir.log" >&2; die "hystloop-logger did not start"; }
}

# Stops the recorder (SIGINT: it flushes) and sets recorded_log to the one log it wrote.
# Not in a $(...) subshell: only this shell can wait for the recorder.
stop_recorder() {
  local dir="$1"
  kill -INT "$recorder_pid" 2>/dev/null || true
  wait "$recorder_pid" || true
  recorder_pid=""
  local files=("$dir"/*.lcmlog)
  [ "${#files[@]}" = 1 ] && [ -f "${files[0]}" ] || die "expected one log in $dir, found: ${files[*]}"
  recorded_log="${files[0]}"
}
