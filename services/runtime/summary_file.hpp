#pragma once
// The services' --summary-json files: one JSON library (nlohmann), keys in the order written, and
// one way to put a file on disk so that a script never reads half of one.

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "core/latency_stats.hpp"

namespace hystloop {

// Pretty-printed (2 spaces), ASCII only: text that came off the wire and is not valid UTF-8 is
// replaced (U+FFFD), never a reason to lose the summary.
std::string to_json_text(const nlohmann::ordered_json& value);

// Writes `text` to `path` through a temporary file and a rename, so a reader never sees half of
// it; the temporary file is removed if that fails. Throws std::runtime_error naming the path.
void write_file_atomically(const std::filesystem::path& path, const std::string& text);

// A run's summary: written as above; a failure is logged, not thrown (the run itself is over and
// its exit code stands).
void write_summary_file(const std::filesystem::path& path, const nlohmann::ordered_json& value) noexcept;

// {"p50", "p99", "max"} [us], one decimal as the log lines print them (-1 with nothing recorded),
// and "count".
nlohmann::ordered_json latency_summary_us(const LatencyStats& stats);

}  // namespace hystloop
