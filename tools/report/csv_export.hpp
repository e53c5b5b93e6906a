#pragma once
// CSV export of whole logged channels: the channel's table (channel_table.hpp: one row per
// event, per tick for the blocks of HX_SENSOR and HX_COMMAND) as a header line of its column
// names (t_s and recv_utime_us first: the row's time on the report's axis and the event's raw
// log timestamp) and one line per row. A text is quoted; a ragged column's part of a row (a
// trajectory's points, a status's counters) is one quoted field of space-separated values. An
// event that does not decode is skipped and counted. Beside each CSV, <channel>.legend.txt
// names the codes of its integer-coded columns: "mode: 0=off,1=linear,...", one column a line.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "channel_table.hpp"

namespace hystloop::report {

struct CsvExport {
  std::string channel;
  std::filesystem::path file;         // DIR/<channel>.csv, characters outside [A-Za-z0-9_.-] replaced by '_'
  std::filesystem::path legend_file;  // DIR/<channel>.legend.txt, the name made safe alike
  std::string type_name;              // "hystloop.sensor_block_t", or "unknown" (rows carry only times and size)
  std::size_t rows = 0;               // rows written (ticks of a block channel)
  std::size_t skipped = 0;            // events that did not decode
};

// The text of a channel's legend file: a comment line naming the CSV and its type, then one
// line per column of the table that has a legend, "column: codes".
std::string csv_legend_text(const ChannelTable& table);

// One pass over the logs, writing each channel's rows with lower_s <= t_s <= upper_s
// (t_s relative to t0_utime; a block's rows are the ticks of `axis`), and each channel's legend
// file. Throws std::runtime_error if a file cannot be written.
std::vector<CsvExport> export_csv(const std::vector<std::filesystem::path>& logs,
                                  const std::vector<std::string>& channels, std::int64_t t0_utime, double lower_s,
                                  double upper_s, const std::filesystem::path& dir, int axis = 0);

}  // namespace hystloop::report
