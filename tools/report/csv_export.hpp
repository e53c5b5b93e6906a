#pragma once
// CSV export of whole logged channels: one row per event (per tick for the blocks of
// HX_SENSOR and HX_COMMAND, the block's fields repeated on each), a header naming every
// decoded field with its unit (t_s and recv_utime_us first: the row's time on the report's
// axis and the event's raw log timestamp). The message type is recognised from its
// fingerprint, so any channel of any rig prefix exports; an event that does not decode is
// skipped and counted. Beside each CSV, <channel>.legend.txt names the codes of its
// integer-coded columns (code_legend.hpp): "mode: 0=off,1=linear,...", one column a line.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace hystloop::report {

struct CsvExport {
  std::string channel;
  std::filesystem::path file;
  std::filesystem::path legend_file;  // DIR/<channel>.legend.txt
  std::string type_name;              // "hystloop.sensor_block_t", or "unknown" (rows carry only times and size)
  std::size_t rows = 0;               // rows written (ticks of a block channel)
  std::size_t skipped = 0;            // events that did not decode
};

// File name for a channel: DIR/<channel>.csv, characters outside [A-Za-z0-9_.-] replaced by '_'.
std::filesystem::path csv_path(const std::filesystem::path& dir, const std::string& channel);

// DIR/<channel>.legend.txt, the channel's name made safe as for csv_path.
std::filesystem::path csv_legend_path(const std::filesystem::path& dir, const std::string& channel);

// The text of a channel's legend file: a comment line naming the CSV and its type, then one
// line per integer-coded column of `csv_header` ("t_s,recv_utime_us,...") that the type's
// legend knows, "column: codes".
std::string csv_legend_text(const std::string& channel, const std::string& type_name, const std::string& csv_header);

// One pass over the logs, writing each channel's rows with lower_s <= t_s <= upper_s
// (t_s relative to t0_utime), and each channel's legend file. Throws std::runtime_error if a file cannot be written.
std::vector<CsvExport> export_csv(const std::vector<std::filesystem::path>& logs,
                                  const std::vector<std::string>& channels, std::int64_t t0_utime, double lower_s,
                                  double upper_s, const std::filesystem::path& dir);

}  // namespace hystloop::report
