#include "logger/logger_options.hpp"

#include <glib.h>

#include <array>
#include <vector>

namespace hystloop {

namespace {
struct FlagSpec {
  const char* flag;
  const char* key;  // under logger.
  const char* help;
  const char* type;   // shown in --help
  bool text = false;  // a string: quoted for YAML, so "[A-Z]_.*" stays a string
};

std::string yaml_single_quoted(const std::string& text) {
  std::string out = "'";
  for (const char c : text) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

// The check LCM's lcm_subscribe makes on a channel regex (GLib's GRegex on "^REGEX$"): the
// reason it refuses one, or "" if it accepts it. Done here so a bad --channels is refused
// with the other options (exit 2), and because LCM 1.3.1 leaks a string when it refuses one.
std::string lcm_regex_error(const std::string& regex) {
  const std::string anchored = "^" + regex + "$";
  GError* error = nullptr;
  GRegex* compiled =
      g_regex_new(anchored.c_str(), static_cast<GRegexCompileFlags>(0), static_cast<GRegexMatchFlags>(0), &error);
  if (compiled != nullptr) g_regex_unref(compiled);
  if (error == nullptr) return {};
  std::string reason = error->message;
  g_error_free(error);
  return reason;
}

constexpr std::array<FlagSpec, 11> kFlags{{
    {"--out-dir", "out_dir", "Directory of the log files (default logs)", "DIR", true},
    {"--file-prefix", "file_prefix", "Text prepended to every file name (default none)", "TEXT", true},
    {"--max-file-mb", "max_file_mb", "Rotate before a file passes this size [10^6 bytes]; 0 = never (default 1024)",
     "MB"},
    {"--max-file-s", "max_file_s", "Rotate a file once it is this old [s]; 0 = never (default 0)", "S"},
    {"--summary", "summary", "Summary JSON written at close (default <out-dir>/<recording>.summary.json)", "FILE",
     true},
    {"--channels", "channels", "Regular expression of the channels recorded (default the rig's, <rig>.*)", "REGEX",
     true},
    {"--queue-mb", "queue_mb", "Buffer between receiving and disk [10^6 bytes] (default 64)", "MB"},
    {"--lcm-queue", "lcm_queue", "Messages LCM holds for the logger before dropping (default 20000)", "N"},
    {"--flush-interval-s", "flush_interval_s", "How often buffered events are handed to the kernel [s] (default 0.2)",
     "S"},
    {"--restart-threshold", "restart_threshold",
     "A seq step back by more than this many ticks is a sender restart, not a late message (default 10000)", "N"},
    {"--command-resume-s", "command_resume_s",
     "Commands silent this long [s], then starting at a later tick: a resume of the compensator, counted as "
     "skipped ticks, not as a gap; 0 = always a gap (default 0.1)",
     "S"},
}};
}  // namespace

void add_logger_options(CLI::App& app, LoggerFlags& flags) {
  for (const FlagSpec& spec : kFlags) {
    app.add_option(spec.flag, flags.values[spec.key], spec.help)->type_name(spec.type)->group("Logger");
  }
}

void apply_logger_flags(const LoggerFlags& flags, Config& config) {
  for (const FlagSpec& spec : kFlags) {
    const auto it = flags.values.find(spec.key);
    if (it == flags.values.end() || it->second.empty()) continue;
    config.apply_override(std::string("logger.") + spec.key + "=" +
                          (spec.text ? yaml_single_quoted(it->second) : it->second));
  }
}

LoggerOptions read_logger_options(const Config& config) {
  // Keys outside logger.* belong to other processes sharing the file.
  std::vector<std::string> known;
  for (const FlagSpec& spec : kFlags) known.push_back(std::string("logger.") + spec.key);
  for (const std::string& key : config.keys()) {
    if (key.rfind("logger.", 0) != 0) known.push_back(key);
  }
  config.check_no_unknown_keys(known);

  LoggerOptions o;
  o.out_dir = config.get<std::string>("logger.out_dir", o.out_dir.string());
  if (o.out_dir.empty()) config.fail("logger.out_dir", "must not be empty");
  o.file_prefix = config.get<std::string>("logger.file_prefix", o.file_prefix);
  if (o.file_prefix.find('/') != std::string::npos) config.fail("logger.file_prefix", "must not contain '/'");
  o.max_file_mb = config.get_in_range("logger.max_file_mb", o.max_file_mb, 0.0, 1e9);
  o.max_file_s = config.get_in_range("logger.max_file_s", o.max_file_s, 0.0, 1e9);
  o.summary_file = config.get<std::string>("logger.summary", "");
  // Refused now rather than found out at shutdown, after the whole recording.
  if (!o.summary_file.empty() && (std::filesystem::is_directory(o.summary_file) || o.summary_file.filename().empty())) {
    config.fail("logger.summary", "'" + o.summary_file.string() + "' is a directory; give the summary file's path");
  }
  o.channels = config.get<std::string>("logger.channels", "");
  if (const std::string reason = lcm_regex_error(o.channels); !reason.empty()) {
    config.fail("logger.channels", "not a regular expression LCM accepts: " + reason);
  }
  o.queue_mb = config.get_in_range("logger.queue_mb", o.queue_mb, 0.01, 2000.0);
  o.lcm_queue = config.get_int_in_range("logger.lcm_queue", o.lcm_queue, 1, 10000000);
  o.flush_interval_s = config.get_in_range("logger.flush_interval_s", o.flush_interval_s, 0.001, 60.0);
  o.restart_threshold = config.get_int_in_range("logger.restart_threshold", o.restart_threshold, 1, INT64_MAX);
  o.command_resume_s = config.get_in_range("logger.command_resume_s", o.command_resume_s, 0.0, 3600.0);
  return o;
}

}  // namespace hystloop
