#include "log_experiments.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <set>
#include <sstream>
#include <utility>

#include <lcm/lcm-cpp.hpp>

#include "core/errors.hpp"
#include "decode.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "lcm/blocks.hpp"
#include "log_samples.hpp"

namespace hystloop {
namespace {

struct Request {
  std::int64_t log_utime = 0;
  std::int64_t id = 0;
  ExperimentSpec spec;
};

struct Command {  // one command tick
  std::int64_t seq = 0;
  std::int64_t log_utime = 0;  // of its block
  double u_ff_V = 0.0;         // what the compensator commanded (an experiment's voltage; no servo then)
  bool experiment = false;
};

struct Sample {  // one sensor tick
  std::int64_t seq = 0;
  double u_V = 0.0;
  double y_m = 0.0;
  std::int32_t flags = 0;
};

struct Record {
  std::vector<Request> starts;      // log order, distinct ids, valid
  std::vector<std::int64_t> stops;  // log times of STOP_EXPERIMENT requests
  std::vector<Command> commands;    // by seq, distinct
  std::vector<Sample> samples;      // by seq, distinct
};

std::string label(const LoggedExperiment& e) {
  return std::string(e.spec.multisine ? "multisine"
                     : e.spec.settle  ? "settle"
                                      : "sine") +
         " " + number_text(e.spec.offset_V) + " V + " + number_text(e.spec.amplitude_V) + " V at " +
         number_text(e.spec.frequency_hz) + " Hz (request " + std::to_string(e.request_id) + ")";
}

// A request the compensator takes as its own (addressed to it, or to everyone).
bool for_compensator(const control_t& control, const ExperimentLogOptions& o) {
  return control.target.empty() || control.target == o.compensator_process;
}

Record read_record(const std::vector<std::string>& files, const ExperimentLogOptions& o, LoggedExperiments& out) {
  Record r;
  std::set<std::int64_t> ids;
  control_t control{};
  command_block_t command{};
  sensor_block_t sensor{};
  const auto signature_notes = for_each_log_event(files, [&](const std::string&, const lcm::LogEvent& event) {
    if (event.channel == o.sensor_channel) {
      if (report::decode_checked(event, sensor)) {
        require_axis_in(sensor, o.axis, event.channel + " event " + std::to_string(event.eventnum));
        for_each_tick(
            sensor,
            [&](const SensorTick& t) {
              r.samples.push_back({t.seq, t.u_V, t.y_m, t.flags});
            },
            static_cast<std::size_t>(o.axis));
      }
    } else if (event.channel == o.command_channel) {
      if (report::decode_checked(event, command) && o.axis < static_cast<int>(axes_of(command))) {
        for_each_tick(
            command,
            [&](const CommandTick& t) {
              r.commands.push_back({t.seq, event.timestamp, t.u_ff_V, t.mode == command_block_t::MODE_EXPERIMENT});
            },
            static_cast<std::size_t>(o.axis));
      }
    } else if (event.channel == o.control_channel) {
      if (!report::decode_checked(event, control)) return;
      if (!for_compensator(control, o)) return;
      if (control.command == control_t::STOP_EXPERIMENT) return r.stops.push_back(event.timestamp);
      if (control.command != control_t::START_EXPERIMENT || !ids.insert(control.request_id).second) return;
      try {  // what the compensator accepts (CompensatorService::on_control)
        ExperimentSpec spec =
            make_experiment_spec(control.experiment, control.experiment_amplitude_V, control.experiment_offset_V,
                                 control.experiment_frequency_Hz, control.experiment_duration_s);
        prepare_experiment(spec, o.dt_s);  // a multisine's samples, as the compensator designed them
        r.starts.push_back({event.timestamp, control.request_id, std::move(spec)});
      } catch (const ParameterError& e) {
        out.notes.push_back("request " + std::to_string(control.request_id) +
                            ": refused by the compensator's rules: " + e.what());
      }
    }
  });
  out.notes.insert(out.notes.end(), signature_notes.begin(), signature_notes.end());
  out.files = files.size();
  out.requests = r.starts.size();
  auto by_seq = [](const auto& a, const auto& b) { return a.seq < b.seq; };
  auto same_seq = [](const auto& a, const auto& b) { return a.seq == b.seq; };
  std::stable_sort(r.commands.begin(), r.commands.end(), by_seq);
  r.commands.erase(std::unique(r.commands.begin(), r.commands.end(), same_seq), r.commands.end());
  std::stable_sort(r.samples.begin(), r.samples.end(), by_seq);
  r.samples.erase(std::unique(r.samples.begin(), r.samples.end(), same_seq), r.samples.end());
  return r;
}

// A run of EXPERIMENT command ticks: ticks first..last logged; the run certainly ended by end_max
// (the next logged non-experiment command tick, or last + 1 when the log ends).
struct Block {
  std::int64_t first = 0, last = 0, end_max = 0;
  std::int64_t first_log_utime = 0, last_log_utime = 0;
  std::size_t first_index = 0;  // into Record::commands
};

std::vector<Block> find_blocks(const std::vector<Command>& commands) {
  std::vector<Block> blocks;
  for (std::size_t i = 0; i < commands.size();) {
    if (!commands[i].experiment) {
      ++i;
      continue;
    }
    Block b{commands[i].seq, commands[i].seq, 0, commands[i].log_utime, commands[i].log_utime, i};
    std::size_t j = i;
    while (j < commands.size() && commands[j].experiment) {
      b.last = commands[j].seq;
      b.last_log_utime = std::max(b.last_log_utime, commands[j].log_utime);
      ++j;
    }
    b.end_max = j < commands.size() ? commands[j].seq : b.last + 1;
    blocks.push_back(b);
    i = j;
  }
  return blocks;
}

struct Mismatch {
  std::int64_t tick = 0;
  double expected_V = 0.0, commanded_V = 0.0;
};

// The first logged command of [begin, end) that is not the requested sine, if any.
std::optional<Mismatch> first_mismatch(const std::vector<Command>& commands, std::size_t& index,
                                       const ExperimentSpec& e, double start_s, std::int64_t begin, std::int64_t end,
                                       double dt_s) {
  while (index < commands.size() && commands[index].seq < begin) ++index;
  // The compensator ramps to an excitation that starts away from where the plan is (another
  // experiment's offset) within the slew limit: until the commands meet the sine, each moves from
  // the previous one towards it.
  bool ramping = true;
  double previous = std::numeric_limits<double>::quiet_NaN();
  for (; index < commands.size() && commands[index].seq < end; ++index) {
    const Command& c = commands[index];
    // Loop time as the compensator computes it (Compensator::loop_time).
    const double expected = experiment_voltage(e, static_cast<double>(c.seq) * dt_s - start_s);
    const double tolerance = 1e-9 * (1.0 + std::abs(expected));
    const bool exact = c.experiment && std::abs(c.u_ff_V - expected) <= tolerance;
    const bool towards = c.experiment && ramping &&
                         (std::isnan(previous) || (c.u_ff_V >= std::min(previous, expected) - tolerance &&
                                                   c.u_ff_V <= std::max(previous, expected) + tolerance));
    if (!exact && !towards) return Mismatch{c.seq, expected, c.u_ff_V};
    if (exact) ramping = false;
    previous = c.u_ff_V;
  }
  return std::nullopt;
}

void collect_samples(const std::vector<Sample>& samples, const ExperimentLogOptions& o, LoggedExperiment& e) {
  const double dt_s = o.dt_s;
  auto it = std::lower_bound(samples.begin(), samples.end(), e.begin_tick,
                             [](const Sample& s, std::int64_t seq) { return s.seq < seq; });
  constexpr std::int32_t kNotAsCommanded = std::int32_t{sensor_block_t::LATE_COMMAND} |
                                           std::int32_t{sensor_block_t::SATURATED} |
                                           std::int32_t{sensor_block_t::SLEW_LIMITED};
  std::int64_t expected_seq = e.begin_tick;
  for (; it != samples.end() && it->seq < e.end_tick; ++it) {
    e.missing += static_cast<std::size_t>(it->seq - expected_seq);
    expected_seq = it->seq + 1;
    if ((it->flags & sensor_block_t::SAFE_STATE) != 0) {
      ++e.safe_state;
      continue;
    }
    if ((it->flags & sensor_block_t::SENSOR_FAULT) != 0) {
      ++e.sensor_fault;
      continue;
    }
    if ((it->flags & kNotAsCommanded) != 0) ++e.not_as_commanded;
    e.samples.t.push_back(static_cast<double>(it->seq - e.begin_tick) * dt_s);
    e.samples.u.push_back(it->u_V);
    e.samples.y.push_back(it->y_m);
  }
  e.missing += static_cast<std::size_t>(std::max<std::int64_t>(0, e.end_tick - expected_seq));
  if (!e.problem.empty()) return;
  const auto ticks = static_cast<double>(e.end_tick - e.begin_tick);
  const bool loop = e.spec.frequency_hz < o.rate_independent_below_Hz;
  if (e.missing > 0 && (!loop || static_cast<double>(e.missing) > o.max_missing * ticks)) {
    e.problem = std::to_string(e.missing) + " tick(s) without a sample in the log" +
                (loop ? ", more than " + number_text(o.max_missing * 100.0) + " %" : " (its time base matters)");
  } else if (e.safe_state > 0) {
    e.problem = std::to_string(e.safe_state) + " sample(s) in the safe state (watchdog trip or disarmed)";
  } else if (e.sensor_fault > 0) {
    e.problem = std::to_string(e.sensor_fault) + " sample(s) flagged SENSOR_FAULT";
  } else if (!loop && static_cast<double>(e.not_as_commanded) > o.max_not_as_commanded * ticks) {
    e.problem = std::to_string(e.not_as_commanded) +
                " sample(s) not applied as commanded (late, saturated or "
                "slew-limited), more than " +
                number_text(o.max_not_as_commanded * 100.0) + " %";
  }
}

}  // namespace

void ExperimentLogOptions::validate() const {
  if (control_channel.empty() || command_channel.empty() || sensor_channel.empty()) {
    throw ParameterError("rig", "channel names must not be empty");
  }
  require_positive("dt", dt_s);
  require_in_range("max_not_as_commanded", max_not_as_commanded, 0.0, 1.0);
  require_in_range("max_missing", max_missing, 0.0, 1.0);
  require_positive("rate_independent_below_Hz", rate_independent_below_Hz);
  require_in_range("axis", axis, 0, sensor_block_t::MAX_AXES - 1);
}

LoggedExperiments read_logged_experiments(const std::vector<std::string>& files, const ExperimentLogOptions& o) {
  o.validate();
  if (files.empty()) throw SampleLogError("no log file given");
  LoggedExperiments out;
  const Record r = read_record(files, o, out);
  const std::vector<Block> blocks = find_blocks(r.commands);
  out.blocks = blocks.size();
  const std::string where = files.size() == 1 ? files.front() : files.front() + " ... " + files.back();
  if (blocks.empty()) {
    throw SampleLogError(where + ": no experiment ran (no " + o.command_channel + " command tick in mode EXPERIMENT; " +
                         std::to_string(r.commands.size()) + " command ticks, " + std::to_string(out.requests) +
                         " START_EXPERIMENT requests logged)");
  }
  out.first_sample_seq = r.samples.empty() ? 0 : r.samples.front().seq;
  std::size_t next = 0;  // first request not yet accounted for
  for (std::size_t bi = 0; bi < blocks.size(); ++bi) {
    const Block& b = blocks[bi];
    std::size_t last = next;  // requests logged before the block's end: [next, last)
    while (last < r.starts.size() && r.starts[last].log_utime <= b.last_log_utime) ++last;
    if (last == next) {
      out.notes.push_back("experiment commands at ticks " + std::to_string(b.first) + ".." + std::to_string(b.last) +
                          " follow no START_EXPERIMENT request in the log (was it recorded from the start?)");
      continue;
    }
    std::vector<ExperimentSpec> specs;
    for (std::size_t i = next; i < last; ++i) specs.push_back(r.starts[i].spec);
    const std::vector<ExperimentTicks> ticks = experiment_schedule(b.first, specs, o.dt_s);
    double start_s = static_cast<double>(b.first) * o.dt_s;
    std::size_t command_index = b.first_index;
    std::string mismatch;  // once found, the rest of the block is unexplained
    bool cut = false;
    std::size_t i = next;
    for (; i < last && ticks[i - next].begin < b.end_max; ++i) {
      LoggedExperiment e;
      e.request_id = r.starts[i].id;
      e.spec = r.starts[i].spec;
      e.begin_tick = ticks[i - next].begin;
      e.end_tick = ticks[i - next].end;
      e.complete = e.end_tick <= b.end_max;
      if (!mismatch.empty()) {
        e.problem = mismatch;
      } else if (const auto m = first_mismatch(r.commands, command_index, e.spec, start_s, e.begin_tick,
                                               std::min(e.end_tick, b.end_max), o.dt_s)) {
        mismatch = "the commands differ from the requested sines from tick " + std::to_string(m->tick) + " (expected " +
                   number_text(m->expected_V) + " V, commanded " + number_text(m->commanded_V) +
                   " V): a request is missing from the log";
        e.problem = mismatch;
      } else if (!e.complete) {
        e.problem = "cut short at tick " + std::to_string(b.last) + " (STOP_EXPERIMENT, or the compensator restarted)";
        cut = true;
      }
      e.end_tick = std::min(e.end_tick, b.end_max);
      start_s = experiment_end_s(start_s, e.spec);
      collect_samples(r.samples, o, e);
      out.experiments.push_back(std::move(e));
      if (cut) {
        ++i;
        break;
      }
    }
    const std::int64_t explained = out.experiments.empty() ? b.first : out.experiments.back().end_tick;
    if (mismatch.empty() && !cut && explained < b.last + 1) {
      out.notes.push_back("ticks " + std::to_string(explained) + ".." + std::to_string(b.last) +
                          " ran an experiment no logged request explains (a request missing from the log?)");
    }
    // Requests logged before this block ended that did not run in it: dropped with the queue
    // when it was cut short or stopped; otherwise they start the next block.
    const std::int64_t next_block_utime = bi + 1 < blocks.size() ? blocks[bi + 1].first_log_utime : INT64_MAX;
    const bool stopped = cut || std::any_of(r.stops.begin(), r.stops.end(), [&](std::int64_t t) {
                           return t >= b.first_log_utime && t < next_block_utime;
                         });
    if (stopped) {
      for (; i < last; ++i) {
        out.notes.push_back("request " + std::to_string(r.starts[i].id) + " never ran (dropped by STOP_EXPERIMENT)");
      }
    }
    next = i;
  }
  for (; next < r.starts.size(); ++next) {
    out.notes.push_back("request " + std::to_string(r.starts[next].id) + " did not run before the log ends");
  }
  return out;
}

std::size_t count_experiment_requests(const std::vector<std::string>& files, const ExperimentLogOptions& o) {
  std::set<std::int64_t> ids;
  control_t control{};
  try {
    for_each_log_event(files, [&](const std::string&, const lcm::LogEvent& event) {
      if (event.channel != o.control_channel) return;
      if (!report::decode_checked(event, control)) return;
      if (for_compensator(control, o) && control.command == control_t::START_EXPERIMENT) ids.insert(control.request_id);
    });
  } catch (const SampleLogError&) {
    return 0;  // the reader then says why
  }
  return ids.size();
}

std::string describe(const LoggedExperiments& logged) {
  std::ostringstream o;
  std::size_t usable = 0, measured = 0;
  for (const auto& e : logged.experiments) {
    measured += e.spec.settle ? 0 : 1;
    usable += (!e.spec.settle && e.usable()) ? 1 : 0;
  }
  o << "log: " << logged.files << " file(s), " << logged.requests << " experiment request(s), " << logged.blocks
    << " run(s) of experiment commands, " << logged.experiments.size() << " experiment(s) ran (" << measured
    << " measured, " << usable << " usable)\n";
  for (std::size_t i = 0; i < logged.experiments.size(); ++i) {
    const auto& e = logged.experiments[i];
    o << "  " << i << ": " << label(e) << ", ticks " << e.begin_tick << ".." << e.end_tick << ": ";
    if (e.usable()) {
      o << (e.spec.settle ? "settling (not fitted)" : "used") << ", " << e.samples.t.size() << " samples";
      if (e.missing > 0) o << ", " << e.missing << " missing";
      if (e.not_as_commanded > 0) o << ", " << e.not_as_commanded << " not as commanded";
    } else {
      o << "skipped: " << e.problem;
    }
    o << "\n";
  }
  for (const auto& n : logged.notes) o << "  note: " << n << "\n";
  return o.str();
}

std::string list_experiments(const LoggedExperiments& logged, const ExperimentLogOptions& options) {
  std::string out = "    N  kind    offset [V]  amplitude [V]  frequency [Hz]  duration [s]  time in the record [s]\n";
  char line[256];
  for (std::size_t i = 0; i < logged.experiments.size(); ++i) {
    const LoggedExperiment& e = logged.experiments[i];
    const char* kind = e.spec.multisine ? "msine" : e.spec.settle ? "settle" : "sine";
    const double from_s = static_cast<double>(e.begin_tick - logged.first_sample_seq) * options.dt_s;
    const double to_s = static_cast<double>(e.end_tick - logged.first_sample_seq) * options.dt_s;
    std::snprintf(line, sizeof line, "  %3zu  %-6s  %10.4g  %13.4g  %14.4g  %12.4g  %9.4f .. %-9.4f  ", i, kind,
                  e.spec.offset_V, e.spec.amplitude_V, e.spec.frequency_hz,
                  static_cast<double>(e.end_tick - e.begin_tick) * options.dt_s, from_s, to_s);
    out += line;
    out += e.usable() ? (e.spec.settle ? "settling, not for fitting" : "usable") : "cannot be used: " + e.problem;
    out += "\n";
  }
  return out;
}

}  // namespace hystloop
