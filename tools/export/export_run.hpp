#pragma once
// hystloop-export's work, apart from its command line: read the logs once, collect the
// channels' tables (channel_table.hpp), add what the log says about the run and the --config
// files, and write the .mat and/or HDF5 file.

#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "export_content.hpp"
#include "mat_file.hpp"

namespace hystloop::exporter {

struct ExportOptions {
  std::vector<std::filesystem::path> logs;
  std::optional<std::filesystem::path> mat;
  std::optional<std::filesystem::path> hdf5;
  std::vector<std::string> channels;   // as logged ("HX_SENSOR") or by suffix ("SENSOR"); empty = every rig channel
  std::optional<double> from_s, to_s;  // [s after the first sensor tick]
  std::vector<std::filesystem::path> configs;
  std::string rig = "HX_";
  MatVersion mat_version = MatVersion::kV5;
  bool quiet = false;  // no progress

  // Throws ParameterError naming the option: no output, --from after --to, a bad --rig.
  void validate() const;
};

// Reads the --config files (each must be YAML); throws ParameterError("--config", ...) naming the file.
std::vector<ConfigFile> read_configs(const std::vector<std::filesystem::path>& files);

// Throws std::runtime_error when `file` could not be created: its folder is missing or not
// writable, or it is a folder. Checked before a long log is read.
void check_writable(const std::filesystem::path& file);

// Reads the logs into an ExportContent. Progress goes to `progress` (nullptr: none) about every
// two seconds. Throws std::runtime_error for a log that cannot be read, ParameterError("--channel")
// for a channel not in the log.
ExportContent collect(const ExportOptions& options, std::FILE* progress);

// validate, check the outputs, collect, write. Returns the exit status (0); throws as above.
int run_export(const ExportOptions& options, std::FILE* progress, std::FILE* out);

}  // namespace hystloop::exporter
