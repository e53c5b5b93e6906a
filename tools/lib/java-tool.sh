# Sourced by tools/spy and tools/logplayer-gui: runs one of LCM's Java tools with hystloop's
# message types, on the running rig's network. Debian's own launchers (/usr/bin/lcm-spy,
# lcm-logplayer-gui) pass -Xincgc, which Java 17 refuses, and their -cp leaves no room for our
# types; this runs the same classes with the jar the build makes
# (build/release/lcmtypes/hystloop_lcmtypes.jar; built if missing).
#
# The caller sets: tool (its name, for messages), java_class, and calls
#   java_tool_main "$@"     options --host-network, --lcm-url URL, --rig PREFIX, -h/--help; every
#                           other argument is collected in java_tool_args for the caller's own use
#   java_tool_exec ARGS...  run java_class with ARGS (after --lcm-url when given): on the host's
#                           network, inside the rig's namespace (deploy/hystloop up), or inside
#                           tools/netns-run when already there
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
host_network=0 url="" rig="HX_" java_tool_args=()

java_tool_main() {
  while [ $# -gt 0 ]; do
    case "$1" in
      -h|--help) awk 'NR == 1 { next } !/^#/ { exit } { sub(/^# ?/, ""); print }' "$0"; exit 0 ;;
      --host-network) host_network=1 ;;
      --lcm-url) [ $# -ge 2 ] || { echo "$tool: --lcm-url needs a value" >&2; exit 2; }; url="$2"; shift ;;
      --rig) [ $# -ge 2 ] || { echo "$tool: --rig needs a value" >&2; exit 2; }; rig="$2"; shift ;;
      *) java_tool_args+=("$1") ;;
    esac
    shift
  done
}

java_tool_exec() {
  local build jar cp ns SUDO=""
  build="${HYSTLOOP_BUILD_DIR:-$here/build}/release"
  jar="${HYSTLOOP_TYPES_JAR:-$build/lcmtypes/hystloop_lcmtypes.jar}"
  if [ ! -f "$jar" ]; then
    "$here/tools/install-deps"
    cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
    cmake --build "$build" --target hystloop_lcmtypes_jar >/dev/null 2>&1 || cmake --build "$build" >/dev/null
  fi
  [ -f "$jar" ] || { echo "$tool: $jar was not built (HYSTLOOP_BUILD_JAVA=OFF?)" >&2; exit 1; }
  cp="$jar:/usr/share/java/lcm.jar:/usr/share/java/jchart2d.jar"
  local java_cmd=(java -Djava.net.preferIPv4Stack=true -Xmx256m -cp "$cp" "$java_class")
  [ -n "$url" ] && java_cmd+=(--lcm-url="$url")
  java_cmd+=("$@")
  [ "$host_network" = 1 ] && exec "${java_cmd[@]}"
  ns="hystloop-$(echo "${rig%_}" | tr 'A-Z' 'a-z')"
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  if $SUDO ip netns list 2>/dev/null | grep -qw "$ns"; then
    exec $SUDO ip netns exec "$ns" "${java_cmd[@]}"
  fi
  if [ -n "${HYSTLOOP_NETNS_PID:-}" ]; then  # already inside tools/netns-run
    exec "${java_cmd[@]}"
  fi
  echo "$tool: no running rig namespace '$ns' (start one with deploy/hystloop up, or pass --host-network)" >&2
  exit 1
}
