#include "log_samples.hpp"

#include "lcm/rig_auth.hpp"
#include "record/record_auth.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include <lcm/lcm-cpp.hpp>

#include "core/errors.hpp"
#include "decode.hpp"
#include "event_file.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/message_checks.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop {
namespace {

constexpr std::size_t kGapsListed = 5;

std::string where(const std::string& file, std::int64_t eventnum) {
  return file + ": event " + std::to_string(eventnum);
}

// Folds the samples of a record into LogSamples, one at a time, in log order.
class RecordBuilder {
 public:
  explicit RecordBuilder(const LogReadOptions& options) : options_(options) {}

  // One block: refused if a tick's u or y is not finite, counted if it breaks the contract,
  // else its ticks in order.
  void add(const std::string& file, std::int64_t eventnum, const sensor_block_t& block) {
    require_axis_in(block, options_.axis, where(file, eventnum));
    const auto axis = static_cast<std::size_t>(options_.axis);
    for_each_tick(
        block,
        [&](const SensorTick& s) {
          if (std::isfinite(s.u_V) && std::isfinite(s.y_m)) return;
          throw SampleLogError(where(file, eventnum) + " (seq " + std::to_string(s.seq) +
                               "): " + (std::isfinite(s.u_V) ? "y_m" : "u_V") +
                               " is not finite (u_V = " + number_text(s.u_V) + ", y_m = " + number_text(s.y_m) + ")");
        },
        axis);
    if (check_message(block) != Verdict::kOk) return void(++out_.undecodable);
    out_.sensor_ticks += static_cast<std::size_t>(block.n_ticks);
    for_each_tick(
        block, [&](const SensorTick& s) { add_tick(file, eventnum, s); }, axis);
    previous_block_first_ = std::max(previous_block_first_.value_or(block.seq), block.seq);
  }

  LogSamples& result() noexcept { return out_; }

 private:
  void add_tick(const std::string& file, std::int64_t eventnum, const SensorTick& s) {
    if (previous_seq_) {
      // A tick again that the last block held (a block logged twice): a repeat.
      if (s.seq <= *previous_seq_ && s.seq >= previous_block_first_.value_or(*previous_seq_)) {
        return void(++out_.duplicates);
      }
      if (s.seq < *previous_seq_) {
        throw SampleLogError(where(file, eventnum) + ": seq goes back from " + std::to_string(*previous_seq_) + " to " +
                             std::to_string(s.seq) +
                             " (files out of order, or the bridge restarted): give the files in recording order");
      }
    } else {
      first_seq_ = s.seq;
      first_utime_ = s.utime;
    }
    const double t = options_.time_base == LogTimeBase::seq ? static_cast<double>(s.seq - first_seq_) * options_.dt_s
                                                            : static_cast<double>(s.utime - first_utime_) * 1e-6;
    const std::int64_t before = previous_seq_.value_or(s.seq - 1);
    previous_seq_ = s.seq;
    if ((options_.from_s && t < *options_.from_s) || (options_.to_s && t >= *options_.to_s)) {
      ++out_.outside_range;
      in_range_before_ = false;
      return;
    }
    // A jump counts only between two samples of the range (entering it is not a gap).
    if (in_range_before_ && s.seq > before + 1) {
      const auto missing = static_cast<std::size_t>(s.seq - before - 1);
      ++out_.gaps;
      out_.missing += missing;
      if (out_.first_gaps.size() < kGapsListed) out_.first_gaps.push_back({before + 1, missing});
    }
    in_range_before_ = true;
    if ((s.flags & sensor_block_t::SAFE_STATE) != 0) return void(++out_.safe_state);
    if ((s.flags & sensor_block_t::SENSOR_FAULT) != 0) return void(++out_.sensor_fault);
    out_.table.t.push_back(t);
    out_.table.u.push_back(s.u_V);
    out_.table.y.push_back(s.y_m);
    if (!out_.first_seq) out_.first_seq = s.seq;
    out_.last_seq = s.seq;
  }

  const LogReadOptions& options_;
  LogSamples out_;
  std::optional<std::int64_t> previous_seq_;
  std::optional<std::int64_t> previous_block_first_;  // first tick of the last block read
  std::int64_t first_seq_ = 0;
  std::int64_t first_utime_ = 0;
  bool in_range_before_ = false;
};

}  // namespace

void require_axis_in(const sensor_block_t& block, int axis, const std::string& where) {
  const int axes = static_cast<int>(axes_of(block));
  if (axis < axes) return;
  std::string names;
  for (int a = 0; a < axes; ++a) {
    names += a == 0 ? "" : a + 1 == axes ? " and " : ", ";
    names += axis_name(a);
  }
  throw SampleLogError(where + ": its blocks carry " + std::to_string(axes) + (axes == 1 ? " axis (" : " axes (") +
                       names + "), not " + std::string(axis_name(axis)) + " (--axis)");
}

void LogReadOptions::validate() const {
  if (sensor_channel.empty()) throw ParameterError("sensor_channel", "must not be empty");
  require_in_range("axis", axis, 0, sensor_block_t::MAX_AXES - 1);
  require_positive("dt", dt_s);
  if (from_s) require_non_negative("from", *from_s);
  if (to_s) {
    require_positive("to", *to_s);
    if (from_s && !(*to_s > *from_s)) {
      throw ParameterError("to",
                           "must be > from (got from " + number_text(*from_s) + ", to " + number_text(*to_s) + ")");
    }
  }
}

std::vector<std::string> for_each_log_event(
    const std::vector<std::string>& files,
    const std::function<void(const std::string& file, const lcm::LogEvent& event)>& on_event) {
  std::vector<std::string> notes;
  RecordCheck check(process_rig_auth());
  for (const auto& file : files) {
    std::optional<report::EventFileReader> log;
    try {
      log.emplace(file);
    } catch (const std::runtime_error& e) {  // "<file>: no such log file", or cannot be opened
      throw SampleLogError(e.what());
    }
    while (const lcm::LogEvent* event = log->next()) {
      if (check.admit(event->channel, event->data, static_cast<std::size_t>(event->datalen), event->timestamp)) {
        on_event(file, *event);
      }
    }
    for (const std::string& note : check.take_notes()) {
      std::string line = file;
      line += ": ";
      line += note;
      notes.push_back(std::move(line));
    }
  }
  return notes;
}

bool looks_like_lcm_log(const std::string& path) { return std::filesystem::path(path).extension() == ".lcmlog"; }

LogSamples read_sample_logs(const std::vector<std::string>& files, const LogReadOptions& options) {
  options.validate();
  if (files.empty()) throw SampleLogError("no log file given");
  RecordBuilder record(options);
  LogSamples& out = record.result();
  sensor_block_t block{};
  out.signature_notes = for_each_log_event(files, [&](const std::string& file, const lcm::LogEvent& event) {
    ++out.events;
    if (event.channel != options.sensor_channel) return;
    ++out.sensor_events;
    if (!report::decode_unchecked(event, block)) return void(++out.undecodable);
    record.add(file, event.eventnum, block);
  });
  out.files = files.size();
  if (out.table.t.empty()) {
    std::ostringstream s;
    s << (files.size() == 1 ? files.front() : files.front() + " ... " + files.back()) << ": no usable "
      << options.sensor_channel << " sample (" << out.sensor_events << " blocks on the channel with "
      << out.sensor_ticks << " ticks, " << out.outside_range << " outside the time range, " << out.skipped()
      << " skipped, " << out.undecodable << " blocks undecodable)";
    throw SampleLogError(s.str());
  }
  return out;
}

std::string describe(const LogSamples& s, const LogReadOptions& options) {
  std::ostringstream o;
  o << "log: " << s.files << " file(s), " << s.events << " events, " << s.sensor_events << " blocks on "
    << options.sensor_channel << " (" << s.sensor_ticks << " ticks)\n";
  o << "samples: " << s.table.t.size() << " kept (seq " << s.first_seq.value_or(0) << " .. " << s.last_seq.value_or(0)
    << ", t " << number_text(s.table.t.front()) << " .. " << number_text(s.table.t.back()) << " s), " << s.outside_range
    << " outside the time range\n";
  o << "skipped: " << s.safe_state << " SAFE_STATE, " << s.sensor_fault << " SENSOR_FAULT, " << s.duplicates
    << " repeated seq, " << s.undecodable << " block(s) undecodable or out of contract\n";
  for (const std::string& note : s.signature_notes) o << "warning: " << note << "\n";
  o << "seq gaps: " << s.gaps << " (" << s.missing << " samples missing)";
  for (const auto& g : s.first_gaps) o << "; seq " << g.first_missing << " +" << g.missing;
  if (s.gaps > s.first_gaps.size()) o << "; ...";
  o << "\n";
  return o.str();
}

}  // namespace hystloop
