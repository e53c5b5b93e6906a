#include "plot_series.hpp"

#include <charconv>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <utility>

#include "hystloop/command_block_t.hpp"
#include "lcm/feedforward_mode.hpp"

namespace hystloop::report {

namespace {

constexpr std::size_t kFlushBytes = 1 << 16;
constexpr std::size_t kGroups = 3;

// Writes each tick of a group (group_of: an index below kGroups, or none to leave it out) to the
// group's file, every step-th tick and the first of every segment; a blank line between segments.
template <class GroupOf, class WriteRow>
std::array<SeriesFile, kGroups> write_groups(const std::vector<TrackPoint>& ticks,
                                             const std::array<std::filesystem::path, kGroups>& paths,
                                             const char* header, std::size_t max_points, GroupOf group_of,
                                             WriteRow write_row) {
  std::array<SeriesFile, kGroups> out;
  std::array<std::unique_ptr<DataFile>, kGroups> files;
  const std::size_t step = decimation_step(ticks.size(), max_points);
  std::optional<std::size_t> previous;  // group of the previous tick
  for (std::size_t i = 0; i < ticks.size(); ++i) {
    const std::optional<std::size_t> g = group_of(ticks[i]);
    const bool segment_start = g != previous;
    previous = g;
    if (!g || (!segment_start && i % step != 0)) continue;
    auto& file = files[*g];
    if (!file) {
      file = std::make_unique<DataFile>(paths[*g]);
      file->text(header);
    } else if (segment_start) {
      file->blank_line();
    }
    write_row(*file, ticks[i], i);
    ++out[*g].rows;
    out[*g].modes.insert(mode_name(ticks[i].mode));
  }
  for (std::size_t g = 0; g < kGroups; ++g) {
    if (!files[g]) continue;
    out[g].file = files[g]->close();
  }
  return out;
}

}  // namespace

DataFile::DataFile(std::filesystem::path path) : path_(std::move(path)) {
  file_ = std::fopen(path_.c_str(), "w");
  if (file_ == nullptr) throw std::runtime_error(path_.string() + ": cannot write");
  buffer_.reserve(kFlushBytes + 256);
}

DataFile::~DataFile() {
  if (file_ != nullptr) std::fclose(file_);
}

void DataFile::flush_if_full() {
  if (buffer_.size() < kFlushBytes) return;
  failed_ = failed_ || std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size();
  buffer_.clear();
}

DataFile& DataFile::text(std::string_view s) {
  buffer_.append(s);
  flush_if_full();
  return *this;
}

namespace {
void append_number(std::string& out, double v) {
  if (!std::isfinite(v)) {
    out.append("NaN");
    return;
  }
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 9);
  out.append(buf, r.ptr);
}
}  // namespace

void write_text_file(const std::filesystem::path& path, std::string_view text) {
  DataFile out(path);
  out.text(text);
  out.close();
}

std::string plot_number(double v) {
  std::string out;
  append_number(out, v);
  return out;
}

DataFile& DataFile::num(double v) {
  if (row_started_) buffer_.push_back(' ');
  row_started_ = true;
  append_number(buffer_, v);
  return *this;
}

DataFile& DataFile::integer(long long v) {
  if (row_started_) buffer_.push_back(' ');
  row_started_ = true;
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  buffer_.append(buf, r.ptr);
  return *this;
}

void DataFile::end_row() {
  buffer_.push_back('\n');
  row_started_ = false;
  flush_if_full();
}

void DataFile::blank_line() {
  if (row_started_) end_row();
  end_row();
}

const std::filesystem::path& DataFile::close() {
  if (file_ == nullptr) return path_;
  failed_ = failed_ || (!buffer_.empty() && std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size());
  buffer_.clear();
  failed_ = std::fclose(file_) != 0 || failed_;
  file_ = nullptr;
  if (failed_) throw std::runtime_error(path_.string() + ": write failed");
  return path_;
}

std::size_t decimation_step(std::size_t n, std::size_t max_points) noexcept {
  if (max_points == 0) return 1;
  return std::max<std::size_t>(1, (n + max_points - 1) / max_points);
}

const char* mode_name(std::int8_t mode) noexcept {
  const auto known = feedforward_mode_from_wire(mode);
  return known ? to_string(*known) : "unknown";
}

TickPhase phase_of(const TrackPoint& p) noexcept {
  if (p.mode == command_block_t::MODE_EXPERIMENT) return TickPhase::kExperiment;
  if (std::isfinite(p.y_ref_m)) return TickPhase::kTracking;
  return TickPhase::kOther;
}

Compensation compensation_of(std::int8_t mode) noexcept {
  switch (mode) {
    case command_block_t::MODE_OFF:
    case command_block_t::MODE_LINEAR: return Compensation::kWithout;
    case command_block_t::MODE_MEM:
    case command_block_t::MODE_PI:
    case command_block_t::MODE_KATALENIC: return Compensation::kWith;
    default: return Compensation::kUnknown;
  }
}

std::array<SeriesFile, 3> write_u_y_series(const std::vector<TrackPoint>& ticks, const std::vector<double>& model_y,
                                           const std::filesystem::path& dir, std::size_t max_points) {
  return write_groups(
      ticks, {dir / "u_y_experiment.dat", dir / "u_y_tracking.dat", dir / "u_y_other.dat"},
      "# t_s u_V y_µm y_model_µm   (y_model: the MEM set in use for the same u; NaN: none)\n", max_points,
      [](const TrackPoint& p) { return std::optional<std::size_t>(static_cast<std::size_t>(phase_of(p))); },
      [&](DataFile& f, const TrackPoint& p, std::size_t i) {
        f.num(p.t_s).num(p.u_V).num(p.y_m * 1e6).num(i < model_y.size() ? model_y[i] * 1e6 : std::nan(""));
        f.end_row();
      });
}

std::array<SeriesFile, 3> write_yref_y_series(const std::vector<TrackPoint>& ticks, const std::filesystem::path& dir,
                                              std::size_t max_points) {
  return write_groups(
      ticks, {dir / "yref_y_without.dat", dir / "yref_y_with.dat", dir / "yref_y_unknown.dat"},
      "# t_s y_ref_µm y_µm   (tracking ticks; a blank line between segments)\n", max_points,
      [](const TrackPoint& p) {
        return std::isfinite(p.y_ref_m) && phase_of(p) == TickPhase::kTracking
                   ? std::optional<std::size_t>(static_cast<std::size_t>(compensation_of(p.mode)))
                   : std::nullopt;
      },
      [](DataFile& f, const TrackPoint& p, std::size_t) {
        f.num(p.t_s).num(p.y_ref_m * 1e6).num(p.y_m * 1e6);
        f.end_row();
      });
}

}  // namespace hystloop::report
