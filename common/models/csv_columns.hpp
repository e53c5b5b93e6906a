#pragma once
// The one CSV reader of sample files (hystloop-model's input and output, hystloop-identify's
// recorded t,u,y): a header row naming the columns, then one sample per row, comma separated,
// finite numbers in C notation whatever the locale (optional spaces around each field). Blank
// lines and lines starting with '#' are skipped. Columns other than the requested ones are
// ignored (the caller is told which, to say so). Everything else is refused with the file, the
// line and the column: "data.csv:7: column 'u': expected a number, got 'abc'".

#include <cstddef>
#include <istream>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/csv_error.hpp"

namespace hystloop {

struct CsvColumns {
  std::vector<std::string> names;           // the requested columns, in the requested order
  std::vector<std::vector<double>> values;  // values[c][row], finite
  std::vector<std::string> text;            // the text column's field of each row; empty without one
  std::vector<std::size_t> lines;           // file line (1-based) of each row
  std::vector<std::string> ignored;         // header names that were not requested
  std::size_t header_line = 0;

  std::size_t rows() const noexcept { return lines.size(); }
};

struct CsvReadOptions {
  bool any_case = false;         // header names match whatever their case ("U" is u)
  std::string_view text_column;  // a column kept as text when the header has it ("experiment")
};

// `file` names the input in messages ("<stdin>" for standard input). Header names match exactly
// (or, with any_case, ignoring case) after trimming spaces and surrounding double quotes; a header
// naming a column twice is refused. At least one data row is required.
CsvColumns read_csv_columns(std::istream& in, const std::string& file, std::span<const std::string_view> required,
                            const CsvReadOptions& options = {});

// Throws CsvError naming the first row whose |value| in `column` exceeds `bound` [unit]: a
// unit mistake (mV, nm?) or corruption, refused where the line can still be named.
void require_within(const CsvColumns& table, std::size_t column, double bound, const char* unit,
                    const std::string& file);

// Throws CsvError naming the first row whose value in `column` does not strictly exceed the
// previous row's (e.g. t for a model with dynamics).
void require_increasing(const CsvColumns& table, std::size_t column, const std::string& file);

// Header, then one row per sample, every value as the shortest text that reads back to the same
// double (as exact as %.17g).
void write_csv_columns(std::ostream& out, std::span<const std::string_view> names,
                       std::span<const std::vector<double>* const> columns);

}  // namespace hystloop
