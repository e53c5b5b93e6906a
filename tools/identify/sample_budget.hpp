#pragma once
// The memory bound of hystloop-identify. A fit holds its whole problem in memory: about
// 150 bytes per sample for --model mem, 300 for --model auto (10 M rows took 1.4 GB and
// 2.9 GB). Above --max-samples (default kDefaultMaxSamples, i.e. ~300 MB for mem, ~600 MB for
// auto) the record is refused with the reason and the ways out: fit a range (--from/--to on a
// log) or keep every K-th sample (--decimate K; the models are rate-independent, so a slow
// record loses nothing but noise averaging). Reading costs another 24 bytes per row; a CSV is
// counted before it is read (count_csv_rows), so an oversized one is refused before it takes
// memory; a log is refused after reading its samples (24 bytes each).
// Measured (1 M samples, this machine): --model mem 146 MB max RSS in 4 s, auto 300 MB in 17 s.

#include <cstddef>
#include <optional>
#include <string>

#include "ident/sample_csv.hpp"

namespace hystloop {

inline constexpr std::size_t kDefaultMaxSamples = 2'000'000;

// Keeps samples 0, stride, 2 stride, ... of every column (stride >= 1; 1 keeps all), and with
// keep_turns the input's turning points between them (decimate_keeping_extremes): a fast line's
// peaks fall between kept samples, and a hysteresis model fed a missed peak starts its next
// branch in the wrong place. Only for the rate-independent models: Banning's fit reads sines
// at a uniform rate.
void decimate(SampleTable& table, std::size_t stride, bool keep_turns);

// Data rows of a CSV (lines that are not blank, not '#' comments, not the header), counted
// without storing them; 0 if the file cannot be read (the reader then says why).
std::size_t count_csv_rows(const std::string& path);

// Why the table cannot be fitted within max_samples (nullopt: it can), with a hint.
std::optional<std::string> over_sample_budget(std::size_t samples, std::size_t max_samples, std::size_t stride);

}  // namespace hystloop
