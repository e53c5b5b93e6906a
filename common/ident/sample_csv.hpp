#pragma once
// Reading recorded samples from CSV (models/csv_columns.hpp: the one reader): a header row naming
// the columns in any case (t, u, y required, SI: seconds, volts, metres; an optional `experiment`
// column groups rows into experiments), then one sample per row. Blank lines and lines starting
// with '#' are skipped; other columns are ignored. A malformed file, or a u or y beyond the
// sanity bounds (fit_checks.hpp), is refused with a message naming the file, line and column.

#include <istream>
#include <string>
#include <vector>

#include "core/csv_error.hpp"

namespace hystloop {

struct SampleTable {
  std::vector<double> t, u, y;          // [s], [V], [m]
  std::vector<std::string> experiment;  // empty unless the column exists
};

SampleTable parse_sample_csv(std::istream& in, const std::string& name);
SampleTable read_sample_csv(const std::string& path);  // throws CsvError (also if unreadable)

// Rows grouped by the experiment column, in order of first appearance (one group without it).
std::vector<SampleTable> split_experiments(const SampleTable& table);

// 1 / median sample interval [Hz]; 0 if fewer than two samples or t does not increase.
double sample_rate_Hz(const std::vector<double>& t);

}  // namespace hystloop
