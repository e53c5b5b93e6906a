#pragma once
// Writes an export as HDF5 (libhdf5's C API):
//   /                      attributes: what the log says about the run (RunAttribute)
//   /config/<name>         one string dataset per --config file (attribute path)
//   /<channel>/            one group per channel (attributes channel, lcm_type, rows, events,
//                          skipped_events)
//   /<channel>/<column>    one 1-D dataset per column: float64, int64 or UTF-8 strings, with the
//                          attributes units, and where they apply description, legend,
//                          count_column (ragged) or per_row
// Every string (attributes and text datasets) is a variable-length UTF-8 string.

#include <filesystem>

#include "export_content.hpp"

namespace hystloop::exporter {

// Replaces `file`. Throws std::runtime_error naming the file when it cannot be written.
void write_hdf5(const std::filesystem::path& file, const ExportContent& content);

}  // namespace hystloop::exporter
