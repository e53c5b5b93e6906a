#pragma once
// A recorded channel as columns: one column per decoded field, one row per event (per tick for
// the blocks of HX_SENSOR and HX_COMMAND, the block's fields repeated on each), each column with
// its unit and, for integer codes, its legend (code_legend.hpp). The message type is recognised
// from its fingerprint, so any channel of any rig prefix exports. The one decoder and column
// naming of hystloop-report's CSV (csv_export.hpp) and hystloop-export's MAT and HDF5 files.
//
// Variable-length arrays of a message (a trajectory's points, a status's counters, a model's PI
// operators) are "ragged" columns: the arrays of all rows one after the other, row r's part
// being the next count_column[r] values (or a fixed number per row: per_row).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

namespace hystloop::report {

enum class ColumnType { kFloat64, kInt64, kText };

struct Column {
  std::string name;  // the field's name with its unit: "u_V", "utime_us"
  std::string unit;  // SI symbol ("s", "V", "m", "m/V", "Hz"), "us", "tick", or "1" (dimensionless, counts, codes)
  std::string description;  // what it is, when the name does not say it; may be empty
  std::string legend;       // integer codes: "0=off,1=linear,..."; empty when the column is not coded
  ColumnType type = ColumnType::kFloat64;
  std::string count_column;  // ragged: the column holding each row's count; empty otherwise
  std::size_t per_row = 0;   // ragged with a fixed count per row (e.g. 8 coefficients); 0 otherwise
  std::vector<double> f64;
  std::vector<std::int64_t> i64;
  std::vector<std::string> text;

  bool ragged() const noexcept { return !count_column.empty() || per_row > 0; }
  std::size_t size() const noexcept;
};

struct ChannelTable {
  std::string channel;
  std::string type_name = "unknown";  // "hystloop.sensor_block_t"; unknown: times and size only
  std::vector<Column> columns;        // t_s and recv_utime_us first
  std::size_t rows = 0;
  std::uint64_t events = 0;   // events on the channel, in the time range or not
  std::uint64_t skipped = 0;  // events that did not decode or broke the message contract

  const Column* find(const std::string& name) const noexcept;
  // Drops the rows collected so far (the columns and counts stay): for a writer that streams them.
  void clear_rows() noexcept;
};

// Collects the rows of the channels `wanted` accepts, with lower_s <= t_s <= upper_s, t_s
// relative to t0_utime [us] (the sensor ticks dated as hystloop-report dates them). A block's rows
// are the ticks of `axis` (0 x, 1 y, 2 z; hystloop-report --axis); a block without it has none.
class TableBuilder {
 public:
  TableBuilder(std::function<bool(const std::string& channel)> wanted, std::int64_t t0_utime, double lower_s,
               double upper_s, int axis = 0);
  ~TableBuilder();
  TableBuilder(const TableBuilder&) = delete;
  TableBuilder& operator=(const TableBuilder&) = delete;

  // The table the event went to (its rows in the range added), nullptr if its channel is not wanted.
  ChannelTable* add(const lcm::LogEvent& event);
  // Events of every channel seen, wanted or not.
  const std::map<std::string, std::uint64_t>& channel_counts() const noexcept;
  // The tables of the wanted channels, in the order their first events came.
  std::vector<ChannelTable> take();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hystloop::report
