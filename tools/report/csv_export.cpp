#include "csv_export.hpp"

#include <algorithm>
#include <fstream>
#include <stdexcept>

#include "core/errors.hpp"
#include "log_reader.hpp"
#include "plot_series.hpp"

namespace hystloop::report {

namespace {

std::string csv_quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + '"';
}

// Value k of a column, unquoted.
std::string value(const Column& c, std::size_t k) {
  switch (c.type) {
    case ColumnType::kFloat64: return number_text(c.f64[k], 12);
    case ColumnType::kInt64: return std::to_string(c.i64[k]);
    default: return c.text[k];
  }
}

std::string header(const ChannelTable& t) {
  std::string out;
  for (const Column& c : t.columns) {
    if (!out.empty()) out += ',';
    out += c.name;
  }
  return out;
}

void write_rows(const ChannelTable& t, std::ostream& out) {
  std::vector<std::size_t> next(t.columns.size(), 0);  // a ragged column's first value of the row
  std::string line;
  for (std::size_t r = 0; r < t.rows; ++r) {
    line.clear();
    for (std::size_t i = 0; i < t.columns.size(); ++i) {
      const Column& c = t.columns[i];
      if (i > 0) line += ',';
      if (!c.ragged()) {
        line += c.type == ColumnType::kText ? csv_quoted(c.text[r]) : value(c, r);
        continue;
      }
      const std::size_t n = c.per_row > 0 ? c.per_row : static_cast<std::size_t>(t.find(c.count_column)->i64[r]);
      std::string values;
      for (std::size_t k = 0; k < n; ++k) {
        if (k > 0) values += ' ';
        values += value(c, next[i]++);
      }
      line += csv_quoted(values);
    }
    out << line << '\n';
  }
}

struct ChannelWriter {
  CsvExport result;
  std::ofstream out;
  bool has_header = false;
};

// DIR/<channel><suffix>, the channel's characters outside [A-Za-z0-9_.-] replaced by '_'.
std::filesystem::path channel_file(const std::filesystem::path& dir, std::string channel, const char* suffix) {
  for (char& c : channel) {
    const bool ok =
        (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-';
    if (!ok) c = '_';
  }
  return dir / (channel + suffix);
}

}  // namespace

std::string csv_legend_text(const ChannelTable& table) {
  std::string out = "# Integer codes of the columns of " + channel_file("", table.channel, ".csv").string() + " (" +
                    table.type_name + "), from the constants of lcmtypes/*.lcm\n";
  bool any = false;
  for (const Column& c : table.columns) {
    if (c.legend.empty()) continue;
    out += c.name + ": " + c.legend + '\n';
    any = true;
  }
  if (!any) out += "# no column of this channel is integer-coded\n";
  return out;
}

std::vector<CsvExport> export_csv(const std::vector<std::filesystem::path>& logs,
                                  const std::vector<std::string>& channels, std::int64_t t0_utime, double lower_s,
                                  double upper_s, const std::filesystem::path& dir, int axis) {
  std::vector<ChannelWriter> writers;
  writers.reserve(channels.size());
  auto writer_of = [&](const std::string& channel) {
    return std::find_if(writers.begin(), writers.end(), [&](const auto& w) { return w.result.channel == channel; });
  };
  for (const auto& channel : channels) {
    if (writer_of(channel) != writers.end()) continue;  // asked for twice
    ChannelWriter& w = writers.emplace_back();
    w.result.channel = channel;
    w.result.file = channel_file(dir, channel, ".csv");
    w.result.legend_file = channel_file(dir, channel, ".legend.txt");
    w.out.open(w.result.file);
    if (!w.out) throw std::runtime_error(w.result.file.string() + ": cannot write");
  }
  // The rows are written and dropped event by event: a long channel is never held whole.
  TableBuilder builder([&](const std::string& channel) { return writer_of(channel) != writers.end(); }, t0_utime,
                       lower_s, upper_s, axis);
  for_each_event(logs, [&](const lcm::LogEvent& e) {
    ChannelTable* t = builder.add(e);
    if (t == nullptr) return;
    ChannelWriter& w = *writer_of(t->channel);
    if (!w.has_header) w.out << header(*t) << '\n';
    w.has_header = true;
    write_rows(*t, w.out);
    w.result.rows += t->rows;
    t->clear_rows();
  });
  const std::vector<ChannelTable> tables = builder.take();
  std::vector<CsvExport> results;
  for (ChannelWriter& w : writers) {
    ChannelTable none;  // a channel without an event: its times only, of no type
    none.channel = w.result.channel;
    const auto seen =
        std::find_if(tables.begin(), tables.end(), [&](const auto& t) { return t.channel == none.channel; });
    const ChannelTable& t = seen == tables.end() ? none : *seen;
    if (!w.has_header) w.out << "t_s,recv_utime_us\n";
    w.result.type_name = t.type_name;
    w.result.skipped = t.skipped;
    w.out.close();
    if (!w.out) throw std::runtime_error(w.result.file.string() + ": write failed");
    write_text_file(w.result.legend_file, csv_legend_text(t));
    results.push_back(w.result);
  }
  return results;
}

}  // namespace hystloop::report
