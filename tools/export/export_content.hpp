#pragma once
// What one export writes, whatever the file format: the channels' tables, what the log says
// about the run, and the configuration files given with --config.

#include <cstdint>
#include <filesystem>
#include <string>
#include <variant>
#include <vector>

#include "channel_table.hpp"

namespace hystloop::exporter {

using report::ChannelTable;
using report::Column;
using report::ColumnType;

// One fact about the run: a text, an integer or a number (units in the name: "time_zero_utime_us").
struct RunAttribute {
  std::string name;  // a MATLAB identifier: letters, digits, '_'
  std::variant<std::string, std::int64_t, double> value;
};

struct ConfigFile {
  std::filesystem::path path;  // as given
  std::string name;            // the file name as an identifier: "compensator_yaml"
  std::string text;            // the whole file
};

struct ExportContent {
  std::vector<ChannelTable> tables;
  std::vector<RunAttribute> run;
  std::vector<ConfigFile> configs;
  std::vector<std::string> warnings;  // for stderr, and in run as log_warnings: damaged files, undecodable events
};

// `text` as a MATLAB identifier (also a safe HDF5 name): [A-Za-z0-9_], starting with a letter
// ("x" put before one that does not), at most max_length characters.
std::string identifier(const std::string& text, std::size_t max_length = 63);

}  // namespace hystloop::exporter
