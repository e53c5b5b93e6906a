#pragma once
// The logger's settings: the `logger:` section of the configuration file, each also a
// command-line flag (a flag is the same as `--set logger.<key>=VALUE` and wins over it):
//
//   --out-dir DIR             logger.out_dir            directory of the logs (default logs)
//   --file-prefix TEXT        logger.file_prefix        prepended to every file name (default none)
//   --max-file-mb MB          logger.max_file_mb        rotate before a file passes this size, 10^6 bytes (0 = never;
//   default 1024)
//   --max-file-s S            logger.max_file_s         rotate a file this old [s] (0 = never; default 0)
//   --summary FILE            logger.summary            summary JSON (default <dir>/<recording>.summary.json;
//                                                       a directory is refused at start)
//   --channels REGEX          logger.channels           channels recorded (default the rig's: "<rig>.*")
//   --queue-mb MB             logger.queue_mb           receive->disk buffer, 10^6 bytes (default 64)
//   --lcm-queue N             logger.lcm_queue          messages LCM holds before dispatch (default 20000)
//   --flush-interval-s S      logger.flush_interval_s   how often buffered events reach the kernel (default 0.2)
//   --restart-threshold N     logger.restart_threshold  seq step back (ticks) taken as a sender restart (default 10000)
//   --command-resume-s S      logger.command_resume_s   HX_COMMAND silent this long, then a jump forward: a resume
//                                                       (counted as skipped ticks), not a gap (0 = always a gap;
//                                                       default 0.1)

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

#include <CLI/CLI.hpp>

#include "core/config.hpp"

namespace hystloop {

struct LoggerOptions {
  std::filesystem::path out_dir = "logs";
  std::string file_prefix;
  double max_file_mb = 1024.0;
  double max_file_s = 0.0;
  std::filesystem::path summary_file;  // empty = next to the logs
  std::string channels;                // empty = the rig's channels
  double queue_mb = 64.0;
  std::int64_t lcm_queue = 20000;
  double flush_interval_s = 0.2;
  std::int64_t restart_threshold = 10000;
  double command_resume_s = 0.1;
};

// Flag values as given on the command line (text), by configuration key.
struct LoggerFlags {
  std::map<std::string, std::string> values;
};

// Adds the flags above to `app`.
void add_logger_options(CLI::App& app, LoggerFlags& flags);

// Merges the flags that were given into `config` as overrides of logger.<key>.
void apply_logger_flags(const LoggerFlags& flags, Config& config);

// Reads and checks the logger section. Throws ConfigError naming the field
// ("--set: logger.max_file_mb: must be >= 0 (got -1)"), also for unknown logger.* keys.
LoggerOptions read_logger_options(const Config& config);

}  // namespace hystloop
