#include "ident/sample_csv.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "ident/fit_checks.hpp"

namespace hystloop {
namespace {

std::string trim(const std::string& s) {
  std::size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream ss(line);
  while (std::getline(ss, field, ',')) out.push_back(trim(field));
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

SampleTable parse_sample_csv(std::istream& in, const std::string& name) {
  SampleTable table;
  std::string line;
  std::size_t line_no = 0;
  std::vector<std::string> header;
  int ct = -1, cu = -1, cy = -1, ce = -1;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    const std::vector<std::string> fields = split(t);
    if (header.empty()) {
      header = fields;
      for (std::size_t i = 0; i < header.size(); ++i) {
        const std::string h = lower(header[i]);
        int* column = h == "t" ? &ct : h == "u" ? &cu : h == "y" ? &cy : h == "experiment" ? &ce : nullptr;
        if (column != nullptr) *column = static_cast<int>(i);
      }
      std::string missing;
      if (ct < 0) missing += " t";
      if (cu < 0) missing += " u";
      if (cy < 0) missing += " y";
      if (!missing.empty()) {
        throw CsvError(name, line_no, "header '" + t + "' lacks column(s)" + missing + " (expected t,u,y in SI units)");
      }
      continue;
    }
    if (fields.size() != header.size()) {
      throw CsvError(name, line_no,
                     std::to_string(fields.size()) + " fields, the header has " + std::to_string(header.size()));
    }
    auto number = [&](int col) {
      const std::string& f = fields[static_cast<std::size_t>(col)];
      char* end = nullptr;
      errno = 0;
      const double v = std::strtod(f.c_str(), &end);
      if (f.empty() || end != f.c_str() + f.size() || errno == ERANGE) {
        throw CsvError(name, line_no,
                       "column '" + header[static_cast<std::size_t>(col)] + "' (" + std::to_string(col + 1) +
                           "): cannot read '" + f + "' as a number");
      }
      return v;
    };
    // Beyond 10 kV or 1 m is a unit mistake (mV, nm?) or corruption: refused here, where the
    // line and column can still be named, rather than fitted into Inf and NaN.
    auto bounded = [&](int col, double bound, const char* unit) {
      const double v = number(col);
      if (std::abs(v) > bound) {
        std::ostringstream s;
        s << "column '" << header[static_cast<std::size_t>(col)] << "' (" << col + 1 << "): " << v << " " << unit
          << " is beyond the sanity bound +-" << bound << " " << unit << " (columns in SI units: s, V, m)";
        throw CsvError(name, line_no, s.str());
      }
      return v;
    };
    table.t.push_back(number(ct));
    table.u.push_back(bounded(cu, kFitMaxAbsVoltage_V, "V"));
    table.y.push_back(bounded(cy, kFitMaxAbsPosition_m, "m"));
    if (ce >= 0) table.experiment.push_back(fields[static_cast<std::size_t>(ce)]);
  }
  if (header.empty()) throw CsvError(name, line_no, "no header row (expected t,u,y)");
  if (table.t.empty()) throw CsvError(name, line_no, "no samples after the header");
  return table;
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
