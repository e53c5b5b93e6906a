#include "ident/sample_csv.hpp"

#include <algorithm>
#include <array>
#include <fstream>
#include <map>
#include <string_view>
#include <utility>

#include "ident/fit_checks.hpp"
#include "models/csv_columns.hpp"

namespace hystloop {

SampleTable parse_sample_csv(std::istream& in, const std::string& name) {
  static constexpr std::array<std::string_view, 3> kColumns{"t", "u", "y"};
  CsvColumns c = read_csv_columns(in, name, kColumns, {.any_case = true, .text_column = "experiment"});
  // Beyond 10 kV or 1 m is a unit mistake (mV, nm?) or corruption: refused here, where the line
  // can still be named, rather than fitted into Inf and NaN.
  require_within(c, 1, kFitMaxAbsVoltage_V, "V", name);
  require_within(c, 2, kFitMaxAbsPosition_m, "m", name);
  return {std::move(c.values[0]), std::move(c.values[1]), std::move(c.values[2]), std::move(c.text)};
}

SampleTable read_sample_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw CsvError(path, 0, "cannot open the file");
  return parse_sample_csv(in, path);
}

std::vector<SampleTable> split_experiments(const SampleTable& table) {
  if (table.experiment.empty()) return {table};
  std::vector<SampleTable> out;
  std::map<std::string, std::size_t> index;
  for (std::size_t k = 0; k < table.t.size(); ++k) {
    auto [it, inserted] = index.emplace(table.experiment[k], out.size());
    if (inserted) out.emplace_back();
    SampleTable& g = out[it->second];
    g.t.push_back(table.t[k]);
    g.u.push_back(table.u[k]);
    g.y.push_back(table.y[k]);
    g.experiment.push_back(table.experiment[k]);
  }
  return out;
}

double sample_rate_Hz(const std::vector<double>& t) {
  if (t.size() < 2) return 0.0;
  std::vector<double> dt(t.size() - 1);
  for (std::size_t k = 1; k < t.size(); ++k) dt[k - 1] = t[k] - t[k - 1];
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
  const double med = dt[dt.size() / 2];
  return med > 0.0 ? 1.0 / med : 0.0;
}

}  // namespace hystloop
