#include "core/logging.hpp"

#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>

#include <string>
#include <vector>

#include "core/edit_distance.hpp"
#include "core/errors.hpp"

namespace hystloop {

spdlog::level::level_enum parse_log_level(std::string_view text) {
  const std::string lower = ascii_lower(text);
  using spdlog::level::level_enum;
  static constexpr std::pair<const char*, level_enum> kLevels[] = {
      {"trace", level_enum::trace},       {"debug", level_enum::debug},  {"info", level_enum::info},
      {"warn", level_enum::warn},         {"warning", level_enum::warn}, {"error", level_enum::err},
      {"critical", level_enum::critical}, {"off", level_enum::off}};
  for (const auto& [name, level] : kLevels) {
    if (lower == name) return level;
  }
  throw ParameterError("log_level", "unknown level '" + std::string(text) +
                                        "' (expected one of: trace, debug, info, warn, error, "
                                        "critical, off)");
}

std::shared_ptr<spdlog::logger> init_logging(std::string_view process_name, std::string_view level,
                                             const std::optional<std::filesystem::path>& log_file) {
  const auto parsed = parse_log_level(level);  // refuse before touching the current set-up
  if (process_name.empty()) throw ParameterError("process_name", "must not be empty");

  std::vector<spdlog::sink_ptr> sinks;
  sinks.push_back(std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
  if (log_file) {
    // spdlog would create missing folders; a typo in a path is refused like every other path.
    const std::filesystem::path folder = log_file->has_parent_path() ? log_file->parent_path() : ".";
    std::error_code ec;
    if (!std::filesystem::is_directory(folder, ec)) {
      throw ParameterError("log_file", "'" + log_file->string() + "': the folder '" + folder.string() +
                                           "' does not exist (create it first)");
    }
    try {
      sinks.push_back(std::make_shared<spdlog::sinks::basic_file_sink_mt>(log_file->string()));
    } catch (const spdlog::spdlog_ex& e) {
      throw ParameterError("log_file", "cannot open '" + log_file->string() + "': " + e.what());
    }
  }
  const std::string name(process_name);
  auto logger = std::make_shared<spdlog::logger>(name, sinks.begin(), sinks.end());
  logger->set_pattern(kLogPattern);
  logger->set_level(parsed);
  logger->flush_on(spdlog::level::warn);

  spdlog::drop(name);  // a second init (tests, a restart) replaces the first
  spdlog::register_logger(logger);
  spdlog::set_default_logger(logger);
  return logger;
}

void flush_logging() noexcept {
  try {
    spdlog::apply_all([](const std::shared_ptr<spdlog::logger>& logger) { logger->flush(); });
  } catch (...) {
    // A sink that cannot flush at the end of main has nowhere left to report to.
  }
}

}  // namespace hystloop
