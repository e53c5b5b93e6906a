#include "sample_budget.hpp"

#include <cctype>
#include <fstream>
#include <vector>

#include "ident/online_model_selector.hpp"

namespace hystloop {
namespace {

template <typename T>
void keep(std::vector<T>& v, const std::vector<std::size_t>& kept) {
  if (v.empty()) return;
  std::size_t n = 0;
  for (const std::size_t k : kept) {     // kept increases: k >= n
    if (k != n) v[n] = std::move(v[k]);  // never onto itself: a self-moved string is left empty
    ++n;
  }
  v.resize(n);
  v.shrink_to_fit();
}

}  // namespace

void decimate(SampleTable& table, std::size_t stride, bool keep_turns) {
  if (stride <= 1 || table.u.empty()) return;
  std::vector<std::size_t> kept;
  if (keep_turns) {
    kept = decimate_keeping_extremes(table.u, stride);
  } else {
    for (std::size_t k = 0; k < table.u.size(); k += stride) kept.push_back(k);
  }
  keep(table.t, kept);
  keep(table.u, kept);
  keep(table.y, kept);
  keep(table.experiment, kept);
}

std::size_t count_csv_rows(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::size_t rows = 0;
  bool header = false;
  while (std::getline(in, line)) {
    std::size_t i = 0;
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i == line.size() || line[i] == '#') continue;
    if (!header) {
      header = true;
      continue;
    }
    ++rows;
  }
  return rows;
}

std::optional<std::string> over_sample_budget(std::size_t samples, std::size_t max_samples, std::size_t stride) {
  if (samples <= max_samples) return std::nullopt;
  const std::size_t suggest = stride * ((samples + max_samples - 1) / max_samples);
  return std::to_string(samples) + " samples" + (stride > 1 ? " after --decimate " + std::to_string(stride) : "") +
         " exceed --max-samples " + std::to_string(max_samples) +
         " (the fit holds its problem in memory, ~150-300 bytes per sample): fit a range (--from/--to on a log), "
         "keep every K-th sample with --decimate " +
         std::to_string(suggest) + ", or raise --max-samples if the memory is there";
}

}  // namespace hystloop
