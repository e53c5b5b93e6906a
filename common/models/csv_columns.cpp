#include "models/csv_columns.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/edit_distance.hpp"
#include "models/param_table.hpp"

namespace hystloop {
namespace {

std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> out;
  while (true) {
    const std::size_t comma = line.find(',');
    out.push_back(trim(line.substr(0, comma)));
    if (comma == std::string_view::npos) return out;
    line.remove_prefix(comma + 1);
  }
}

std::string join(std::span<const std::string_view> names) {
  std::string out;
  for (const auto n : names) {
    if (!out.empty()) out += ',';
    out += n;
  }
  return out;
}

std::string unquote(std::string_view s) {
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = trim(s.substr(1, s.size() - 2));
  return std::string(s);
}

bool all_numbers(const std::vector<std::string_view>& fields) {
  for (const auto f : fields) {
    double v = 0.0;
    if (!parse_finite_double(f, v)) return false;
  }
  return true;
}

}  // namespace

CsvColumns read_csv_columns(std::istream& in, const std::string& file, std::span<const std::string_view> required,
                            const CsvReadOptions& options) {
  CsvColumns table;
  for (const auto r : required) table.names.emplace_back(r);
  table.values.resize(required.size());
  const std::string expected = join(required);
  auto key = [&](std::string_view name) { return options.any_case ? ascii_lower(name) : std::string(name); };

  std::vector<std::string> header;                  // as matched: lower case with any_case
  std::vector<std::size_t> index(required.size());  // field of each requested column
  std::size_t text_index = 0;                       // field of the text column; header.size() when none
  std::string raw;
  std::size_t line_no = 0;
  bool saw_any = false;
  while (std::getline(in, raw)) {
    ++line_no;
    std::string_view line = raw;
    if (line_no == 1 && line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);  // UTF-8 BOM
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    line = trim(line);
    if (!line.empty()) saw_any = true;
    if (line.empty() || line.front() == '#') continue;
    const std::vector<std::string_view> fields = split_fields(line);

    if (header.empty()) {
      if (all_numbers(fields)) {
        throw CsvError(file, line_no,
                       "missing header row: expected column names '" + expected + "', got '" + std::string(line) + "'");
      }
      for (const auto f : fields) header.push_back(key(unquote(f)));
      auto field_of = [&](std::string_view name) {
        return static_cast<std::size_t>(std::find(header.begin(), header.end(), key(name)) - header.begin());
      };
      text_index = options.text_column.empty() ? header.size() : field_of(options.text_column);
      for (auto h = header.begin(); h != header.end(); ++h) {
        const auto at = static_cast<std::size_t>(h - header.begin());
        if (std::find(header.begin(), h, *h) != h)
          throw CsvError(file, line_no, "header names column '" + unquote(fields[at]) + "' twice");
        const bool requested =
            std::any_of(required.begin(), required.end(), [&](std::string_view r) { return key(r) == *h; });
        if (!requested && at != text_index) table.ignored.push_back(unquote(fields[at]));
      }
      std::string missing;
      for (std::size_t c = 0; c < required.size(); ++c) {
        index[c] = field_of(required[c]);
        if (index[c] == header.size()) missing += (missing.empty() ? "'" : ", '") + std::string(required[c]) + "'";
      }
      if (!missing.empty()) {
        throw CsvError(file, line_no,
                       fmt::format("header '{}' lacks column {} (expected '{}', SI units)", line, missing, expected));
      }
      table.header_line = line_no;
      continue;
    }

    if (fields.size() != header.size()) {
      throw CsvError(file, line_no,
                     std::to_string(fields.size()) + " field" + (fields.size() == 1 ? "" : "s") + ", the header has " +
                         std::to_string(header.size()));
    }
    for (std::size_t c = 0; c < required.size(); ++c) {
      const std::string_view text = fields[index[c]];
      double v = 0.0;
      std::string why;
      if (!parse_finite_double(text, v, &why)) {
        throw CsvError(file, line_no, "column '" + table.names[c] + "': " + why + ", got '" + std::string(text) + "'");
      }
      table.values[c].push_back(v);
    }
    if (text_index < header.size()) table.text.emplace_back(fields[text_index]);
    table.lines.push_back(line_no);
  }
  if (in.bad()) throw CsvError(file, line_no, "read error");
  if (header.empty()) {
    throw CsvError(
        file, line_no == 0 ? 1 : line_no,
        std::string(saw_any ? "no header row" : "empty file") + ": expected a header row '" + expected + "'");
  }
  if (table.rows() == 0) throw CsvError(file, table.header_line, "no data rows after the header");
  return table;
}

void require_increasing(const CsvColumns& table, std::size_t column, const std::string& file) {
  const std::vector<double>& v = table.values[column];
  for (std::size_t k = 1; k < v.size(); ++k) {
    if (!(v[k] > v[k - 1])) {
      throw CsvError(file, table.lines[k],
                     "column '" + table.names[column] + "': must increase, got " + format_number(v[k]) + " after " +
                         format_number(v[k - 1]) + " (line " + std::to_string(table.lines[k - 1]) + ")");
    }
  }
}

void require_within(const CsvColumns& table, std::size_t column, double bound, const char* unit,
                    const std::string& file) {
  const std::vector<double>& v = table.values[column];
  for (std::size_t k = 0; k < v.size(); ++k) {
    if (std::abs(v[k]) > bound) {
      throw CsvError(file, table.lines[k],
                     "column '" + table.names[column] + "': " + format_number(v[k]) + " " + unit +
                         " is beyond the sanity bound +-" + format_number(bound) + " " + unit);
    }
  }
}

void write_csv_columns(std::ostream& out, std::span<const std::string_view> names,
                       std::span<const std::vector<double>* const> columns) {
  out << join(names) << '\n';
  const std::size_t rows = columns.empty() ? 0 : columns.front()->size();
  std::string line;
  for (std::size_t k = 0; k < rows; ++k) {
    line.clear();
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (c > 0) line += ',';
      line += format_number((*columns[c])[k]);
    }
    line += '\n';
    out << line;
  }
}

}  // namespace hystloop
