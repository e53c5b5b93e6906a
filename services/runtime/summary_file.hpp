#pragma once
// The services' --summary-json files: one JSON library (nlohmann), keys in the order written, and
// one way to put a file on disk so that a script never reads half of one.

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

namespace hystloop {

// Pretty-printed (2 spaces), ASCII only: text that came off the wire and is not valid UTF-8 is
// replaced (U+FFFD), never a reason to lose the summary.
std::string to_json_text(const nlohmann::ordered_json& value);

// Writes `text` to `path` through a temporary file and a rename, so a reader never sees half of
// it; the temporary file is removed if that fails. Throws std::runtime_error naming the path.
void write_file_atomically(const std::filesystem::path& path, const std::string& text);

}  // namespace hystloop
