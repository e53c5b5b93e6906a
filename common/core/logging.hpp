#pragma once
// One spdlog set-up for every hystloop process: a logger named after the process
// becomes spdlog's default, writing to stderr (coloured on a terminal) and, if
// asked, to a file as well, all with one pattern:
//
//   2026-11-29 07:12:03.123456 bridge[4242] info  armed, u_max_V = 120
//
// Services log from their set-up, status and error paths only; never from the
// per-sample path (spdlog formats and may allocate).

#include <filesystem>
#include <memory>
#include <optional>
#include <string_view>

#include <spdlog/spdlog.h>

namespace hystloop {

// The pattern every sink uses (spdlog syntax): time, process[pid], level, text.
inline constexpr const char* kLogPattern = "%Y-%m-%d %H:%M:%S.%f %n[%P] %^%-5l%$ %v";

// "trace", "debug", "info", "warn" (or "warning"), "error", "critical", "off";
// case-insensitive. Throws ParameterError("log_level") naming the accepted values.
spdlog::level::level_enum parse_log_level(std::string_view text);

// Creates the process logger (replacing one of the same name), makes it the
// default, sets the level, and flushes at warn and above. Throws ParameterError
// ("log_level" or "log_file") for a bad level or a file that cannot be opened.
std::shared_ptr<spdlog::logger> init_logging(std::string_view process_name, std::string_view level = "info",
                                             const std::optional<std::filesystem::path>& log_file = std::nullopt);

// Flushes every logger (at the end of main, and before a deliberate abort).
// Loggers stay usable afterwards.
void flush_logging() noexcept;

}  // namespace hystloop
