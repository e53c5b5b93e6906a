#pragma once
// Writes an export as a MATLAB .mat file (libmatio), level 5 (compressed; MATLAB's default
// "-v7", also read by scipy.io.loadmat) or 7.3 (HDF5-based: variables over 2 GB):
//   <channel>        struct: one N-by-1 field per column (double, int64, or a cell of char)
//   <channel>_meta   struct: channel, lcm_type, rows, events, skipped_events, and the structs
//                    units, description, legend (coded columns only) and ragged (ragged columns:
//                    their count column, or "N per row")
//   hystloop_run     struct: what the log says about the run, config (one char field per
//                    --config file) and config_files (cell of the paths as given)
// A channel's variable name is the channel as an identifier (identifier()).

#include <filesystem>

#include "export_content.hpp"

namespace hystloop::exporter {

enum class MatVersion { kV5, kV73 };

// Replaces `file`. Throws std::runtime_error naming the file when it cannot be written.
void write_mat(const std::filesystem::path& file, const ExportContent& content, MatVersion version);

}  // namespace hystloop::exporter
