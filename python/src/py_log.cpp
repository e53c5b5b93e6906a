// hystloop.read_log: an LCM event log as numpy columns, per channel, through hystloop-report's
// reader (tools/report: event_file's damage-tolerant reading, decode's contract checks,
// channel_table's columns with units, the ones hystloop-report's CSV and hystloop-export write).
// Blocks (HX_SENSOR, HX_COMMAND) are flattened to one row per tick and axis; HX_SIM_TRUTH, which
// the tables leave undecoded, is decoded here and its true positions joined to the sensor rows.
#include <pybind11/stl.h>

#include <array>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "channel_table.hpp"
#include "decode.hpp"
#include "event_file.hpp"
#include "lcm/blocks.hpp"
#include "lcm/channels.hpp"
#include "lcm/rig_auth.hpp"
#include "log_reader.hpp"
#include "py_common.hpp"

namespace hystloop::python {
namespace {

namespace fs = std::filesystem;
using report::ChannelTable;
using report::Column;
using report::ColumnType;

constexpr int kMaxAxes = 3;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Channel {
  std::string name, type_name;
  std::size_t rows = 0;
  std::uint64_t events = 0, skipped = 0;
  py::dict columns, units, descriptions, legends;
  py::dict counters;  // service_status_t: counter name -> value per row (NaN where a row lacks it)
};

struct Log {
  std::vector<std::string> files, warnings;
  py::list scans;
  std::int64_t t0_utime_us = 0;
  std::optional<int> axis;
  std::map<std::string, std::uint64_t> channel_counts;
  py::dict channels;  // name -> Channel, in the order of their first events
  std::string prefix;
};

bool is_block(const ChannelTable& t) {
  return t.type_name == "hystloop.sensor_block_t" || t.type_name == "hystloop.command_block_t";
}

// The rows one event added to each axis's table of its channel.
struct EventRows {
  std::array<std::size_t, kMaxAxes> first{}, count{};
};

// One table of every axis's rows of a block channel: tick by tick, each tick's axes in order, with
// an `axis` column. `order` holds (axis index, row) pairs.
ChannelTable merge_axes(std::vector<ChannelTable*> per_axis, const std::vector<int>& axes,
                        const std::vector<EventRows>& events) {
  std::vector<std::pair<std::size_t, std::size_t>> order;
  for (const EventRows& e : events) {
    // The axes the event has rows of (a block without an axis has none of it) interleave tick by tick.
    std::size_t ticks = 0;
    bool same = true;
    for (std::size_t a = 0; a < per_axis.size(); ++a) {
      if (e.count[a] == 0) continue;
      same = same && (ticks == 0 || e.count[a] == ticks);
      ticks = e.count[a];
    }
    if (same) {
      for (std::size_t i = 0; i < ticks; ++i)
        for (std::size_t a = 0; a < per_axis.size(); ++a)
          if (e.count[a] > 0) order.emplace_back(a, e.first[a] + i);
    } else {
      for (std::size_t a = 0; a < per_axis.size(); ++a)
        for (std::size_t i = 0; i < e.count[a]; ++i) order.emplace_back(a, e.first[a] + i);
    }
  }
  ChannelTable out = *per_axis[0];
  out.rows = order.size();
  for (std::size_t c = 0; c < out.columns.size(); ++c) {
    Column& col = out.columns[c];
    if (col.ragged()) continue;  // blocks have none
    col.f64.clear(), col.i64.clear(), col.text.clear();
    for (const auto& [a, row] : order) {
      const Column& from = per_axis[a]->columns[c];
      switch (col.type) {
        case ColumnType::kFloat64: col.f64.push_back(from.f64[row]); break;
        case ColumnType::kInt64: col.i64.push_back(from.i64[row]); break;
        case ColumnType::kText: col.text.push_back(from.text[row]); break;
      }
    }
  }
  Column axis{"axis", "1", "0 x, 1 y, 2 z", "0=x,1=y,2=z", ColumnType::kInt64, "", 0, {}, {}, {}};
  for (const auto& [a, row] : order) axis.i64.push_back(axes[a]);
  out.columns.push_back(std::move(axis));
  return out;
}

void add_axis_column(ChannelTable& t, int axis) {
  Column c{"axis", "1", "0 x, 1 y, 2 z", "0=x,1=y,2=z", ColumnType::kInt64, "", 0, {}, {}, {}};
  c.i64.assign(t.rows, axis);
  t.columns.push_back(std::move(c));
}

py::object to_python(const Column& c, const ChannelTable& t) {
  auto numbers = [](const auto& values, std::size_t from, std::size_t n) {
    using T = typename std::decay_t<decltype(values)>::value_type;
    return py::object(py::array_t<T>(static_cast<py::ssize_t>(n), values.data() + from));
  };
  auto whole = [&](std::size_t from, std::size_t n) -> py::object {
    switch (c.type) {
      case ColumnType::kFloat64: return numbers(c.f64, from, n);
      case ColumnType::kInt64: return numbers(c.i64, from, n);
      case ColumnType::kText: {
        py::list texts;
        for (std::size_t i = from; i < from + n; ++i) texts.append(c.text[i]);
        return py::module_::import("numpy").attr("array")(texts, py::arg("dtype") = "object");
      }
    }
    return py::none();
  };
  if (!c.ragged()) return whole(0, c.size());
  // A ragged column: one array per row.
  const Column* count = c.count_column.empty() ? nullptr : t.find(c.count_column);
  py::list rows;
  std::size_t at = 0;
  for (std::size_t r = 0; r < t.rows; ++r) {
    std::size_t n = c.per_row;
    if (count != nullptr) n = static_cast<std::size_t>(count->i64[r]);
    n = std::min(n, c.size() - std::min(at, c.size()));
    rows.append(whole(at, n));
    at += n;
  }
  return rows;
}

// service_status_t's counters by name, one value per row.
py::dict counters_of(const ChannelTable& t) {
  py::dict out;
  const Column* names = t.find("counter_names");
  const Column* values = t.find("counter_values");
  const Column* count = t.find("n_counters");
  if (names == nullptr || values == nullptr || count == nullptr) return out;
  std::map<std::string, std::vector<double>> by_name;
  std::vector<std::string> order;
  std::size_t at = 0;
  for (std::size_t r = 0; r < t.rows; ++r) {
    for (std::int64_t i = 0; i < count->i64[r] && at < names->text.size(); ++i, ++at) {
      auto [it, first] = by_name.try_emplace(names->text[at], t.rows, kNaN);
      if (first) order.push_back(names->text[at]);
      it->second[r] = values->type == ColumnType::kInt64 ? static_cast<double>(values->i64[at]) : values->f64[at];
    }
  }
  for (const auto& name : order)
    out[py::str(name)] = py::array_t<double>(static_cast<py::ssize_t>(t.rows), by_name[name].data());
  return out;
}

Channel to_channel(const ChannelTable& t) {
  Channel c;
  c.name = t.channel;
  c.type_name = t.type_name;
  c.rows = t.rows;
  c.events = t.events;
  c.skipped = t.skipped;
  for (const Column& col : t.columns) {
    c.columns[py::str(col.name)] = to_python(col, t);
    c.units[py::str(col.name)] = col.unit;
    c.descriptions[py::str(col.name)] = col.description;
    if (!col.legend.empty()) c.legends[py::str(col.name)] = col.legend;
  }
  if (t.type_name == "hystloop.service_status_t") c.counters = counters_of(t);
  return c;
}

// HX_SIM_TRUTH's true positions, per tick and axis.
struct TruthRow {
  std::int64_t recv_utime = 0, seq = 0;
  int axis = 0;
  double y_true_m = 0.0;
};

// HX_SIM_TRUTH as a table (t_s of the sensor tick with its seq and axis, NaN when none was logged),
// and the sensor table's y_true_m column (NaN where no truth was logged).
ChannelTable truth_table(const std::string& channel, const std::vector<TruthRow>& truth, ChannelTable* sensor,
                         std::uint64_t events, std::uint64_t skipped, bool ranged) {
  std::unordered_map<std::int64_t, std::array<std::size_t, kMaxAxes>> sensor_rows;  // seq -> row per axis
  const Column* seq = sensor != nullptr ? sensor->find("seq") : nullptr;
  const Column* axis = sensor != nullptr ? sensor->find("axis") : nullptr;
  const Column* t_s = sensor != nullptr ? sensor->find("t_s") : nullptr;
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  if (seq != nullptr && axis != nullptr && t_s != nullptr) {
    for (std::size_t r = 0; r < sensor->rows; ++r) {
      auto [it, first] = sensor_rows.try_emplace(seq->i64[r]);
      if (first) it->second.fill(kNone);
      it->second[static_cast<std::size_t>(axis->i64[r])] = r;
    }
  }
  ChannelTable out;
  out.channel = channel;
  out.type_name = "hystloop.sim_truth_t";
  out.events = events;
  out.skipped = skipped;
  auto column = [](const char* name, const char* unit, const char* what, ColumnType type) {
    return Column{name, unit, what, "", type, "", 0, {}, {}, {}};
  };
  Column t_col =
      column("t_s", "s", "time of the sensor tick with this seq and axis (NaN: none logged)", ColumnType::kFloat64);
  Column recv = column("recv_utime_us", "us", "the event's log timestamp", ColumnType::kInt64);
  Column seq_col = column("seq", "1", "tick number", ColumnType::kInt64);
  Column axis_col = column("axis", "1", "0 x, 1 y, 2 z", ColumnType::kInt64);
  axis_col.legend = "0=x,1=y,2=z";
  Column y_true = column("y_true_m", "m", "the simulated stage's true position", ColumnType::kFloat64);
  std::vector<double> sensor_truth(sensor != nullptr ? sensor->rows : 0, kNaN);
  for (const TruthRow& k : truth) {
    double t = kNaN;
    if (const auto it = sensor_rows.find(k.seq); it != sensor_rows.end()) {
      const std::size_t r = it->second[static_cast<std::size_t>(k.axis)];
      if (r != kNone) {
        t = t_s->f64[r];
        sensor_truth[r] = k.y_true_m;
      }
    }
    if (ranged && std::isnan(t)) continue;  // outside the range asked for (its sensor tick is)
    t_col.f64.push_back(t);
    recv.i64.push_back(k.recv_utime);
    seq_col.i64.push_back(k.seq);
    axis_col.i64.push_back(k.axis);
    y_true.f64.push_back(k.y_true_m);
    ++out.rows;
  }
  out.columns = {std::move(t_col), std::move(recv), std::move(seq_col), std::move(axis_col), std::move(y_true)};
  if (sensor != nullptr && !truth.empty()) {
    Column c = column("y_true_m", "m", "the simulated stage's true position (HX_SIM_TRUTH); NaN: none logged",
                      ColumnType::kFloat64);
    c.f64 = std::move(sensor_truth);
    sensor->columns.push_back(std::move(c));
  }
  return out;
}

Log read_log(const std::vector<std::string>& paths, std::optional<int> axis, const std::vector<std::string>& wanted,
             std::optional<double> from_s, std::optional<double> to_s, const std::string& rig, bool warn,
             const std::optional<std::string>& key_file) {
  if (axis && (*axis < 0 || *axis >= kMaxAxes))
    throw PyParameterError("axis", "axis: " + std::to_string(*axis) + " is not 0 (x), 1 (y) or 2 (z)");
  if (from_s && to_s && !(*from_s < *to_s)) throw PyParameterError("to_s", "to_s: must be after from_s");
  std::optional<ChannelNames> names_or;
  try {
    names_or.emplace(rig);
  } catch (const ParameterError& e) {
    throw PyParameterError("rig", std::string("rig: ") + e.what());
  }
  const ChannelNames& names = *names_or;
  std::shared_ptr<const RigAuth> auth;  // nullptr: signatures not checked (a keyed log says so in warnings)
  if (key_file) {
    try {
      auth = rig_auth_from_key_file(*key_file, "key_file");
    } catch (const ParameterError& e) {
      throw PyParameterError("key_file", e.what());
    }
  }
  if (paths.empty()) throw PyParameterError("path", "no log file given");
  std::vector<fs::path> files;
  for (const auto& p : paths) {
    if (!fs::exists(p)) {
      PyErr_SetString(PyExc_FileNotFoundError, (p + ": no such file").c_str());
      throw py::error_already_set();
    }
    files.emplace_back(p);
  }
  Log log;
  log.files = paths;
  log.axis = axis;
  log.prefix = names.prefix;
  std::set<std::string> candidates;
  for (const auto& c : wanted) candidates.insert(c), candidates.insert(names.prefix + c);
  const auto take = [&](const std::string& channel) {
    return wanted.empty() ? channel.rfind(names.prefix, 0) == 0 : candidates.count(channel) != 0;
  };
  std::vector<int> axes;
  if (axis) {
    axes = {*axis};
  } else {
    axes = {0, 1, 2};
  }
  std::vector<std::unique_ptr<report::TableBuilder>> builders;
  std::vector<report::LogFileScan> scans;
  std::map<std::string, std::vector<EventRows>> event_rows;
  std::vector<TruthRow> truth;
  std::uint64_t truth_events = 0, truth_skipped = 0;
  {
    const py::gil_scoped_release unlocked;
    log.t0_utime_us = report::log_time_zero_utime(files, names.sensor, auth);
    for (const int a : axes) {
      builders.push_back(std::make_unique<report::TableBuilder>(take, log.t0_utime_us, from_s.value_or(-1e300),
                                                                to_s.value_or(1e300), a));
    }
    std::map<std::string, std::array<std::size_t, kMaxAxes>> rows_so_far;
    sim_truth_t block;
    const auto visit = [&](const lcm::LogEvent& e) {
      if (e.channel == names.sim_truth && take(e.channel)) {
        ++truth_events;
        if (!report::decode_checked(e, block)) {
          ++truth_skipped;
        } else {
          // Tick by tick, each tick's axes in order, as the sensor rows.
          const std::size_t n_axes = axes_of(block);
          for (std::size_t i = 0; i < ticks_of(block); ++i) {
            for (const int a : axes) {
              const auto at = static_cast<std::size_t>(a);
              if (at < n_axes)
                truth.push_back(
                    {e.timestamp, block.seq + static_cast<std::int64_t>(i), a, block.y_true_m[i * n_axes + at]});
            }
          }
        }
      }
      EventRows rows;
      bool any = false;
      auto& so_far = rows_so_far[e.channel];
      for (std::size_t b = 0; b < builders.size(); ++b) {
        const ChannelTable* t = builders[b]->add(e);
        if (t == nullptr) continue;
        rows.first[b] = so_far[b];
        rows.count[b] = t->rows - so_far[b];
        so_far[b] = t->rows;
        any = any || rows.count[b] > 0;
      }
      if (any && builders.size() > 1) event_rows[e.channel].push_back(rows);
    };
    scans = report::for_each_event(files, visit, auth);
  }
  log.channel_counts = builders.front()->channel_counts();
  std::vector<std::vector<ChannelTable>> tables;
  tables.reserve(builders.size());
  for (auto& b : builders) tables.push_back(b->take());
  std::vector<ChannelTable> out;
  for (std::size_t i = 0; i < tables[0].size(); ++i) {
    ChannelTable& t = tables[0][i];
    if (!is_block(t)) {
      out.push_back(std::move(t));
    } else if (builders.size() == 1) {
      add_axis_column(t, axes[0]);
      out.push_back(std::move(t));
    } else {
      std::vector<ChannelTable*> per_axis;
      for (auto& list : tables) {
        for (auto& other : list) {
          if (other.channel == t.channel) per_axis.push_back(&other);
        }
      }
      out.push_back(merge_axes(per_axis, axes, event_rows[t.channel]));
    }
  }
  if (truth_events > 0) {
    ChannelTable* sensor = nullptr;
    for (auto& t : out) sensor = t.channel == names.sensor ? &t : sensor;
    ChannelTable truth_t = truth_table(names.sim_truth, truth, sensor, truth_events, truth_skipped,
                                       from_s.has_value() || to_s.has_value());
    for (auto& t : out) {
      if (t.channel == names.sim_truth) {
        t = std::move(truth_t);
        break;
      }
    }
  }
  for (const auto& c : wanted) {
    try {
      (void)report::resolve_channel(c, log.channel_counts, names.prefix, "channels");
    } catch (const ParameterError& e) {
      throw PyParameterError("channels", e.what());
    }
  }
  log.warnings = report::describe_scan_problems(scans);
  for (const auto& s : scans) {
    py::dict d;
    d["file"] = s.file;
    d["bytes"] = s.bytes;
    d["events"] = s.events;
    d["skipped_bytes"] = s.skipped_bytes;
    d["trailing_bytes"] = s.trailing_bytes;
    d["recorded_keyed"] = s.recorded_keyed;
    d["unverified_left_out"] = s.unverified_left_out;
    log.scans.append(d);
  }
  for (const ChannelTable& t : out) {
    if (t.skipped > 0) {
      log.warnings.push_back(t.channel + ": " + std::to_string(t.skipped) +
                             " event(s) did not decode or broke the message contract; they are left out");
    }
    log.channels[py::str(t.channel)] = to_channel(t);
  }
  if (warn) {
    for (const auto& w : log.warnings) {
      if (PyErr_WarnEx(PyExc_RuntimeWarning, ("hystloop.read_log: " + w).c_str(), 1) != 0)
        throw py::error_already_set();
    }
  }
  return log;
}

py::object channel_of(const Log& log, const std::string& name) {
  if (log.channels.contains(name)) return log.channels[py::str(name)];
  if (log.channels.contains(log.prefix + name)) return log.channels[py::str(log.prefix + name)];
  std::string list;
  for (auto item : log.channels) list += (list.empty() ? "" : ", ") + py::str(item.first).cast<std::string>();
  throw py::key_error("no channel '" + name + "' read (channels: " + (list.empty() ? "none" : list) + ")");
}

}  // namespace

void register_log(py::module_& m) {
  py::class_<Channel>(m, "Channel", "one channel of a log: columns of numpy arrays with their units")
      .def_readonly("name", &Channel::name, "the channel as logged (HX_SENSOR)")
      .def_readonly("type_name", &Channel::type_name, "its LCM type (hystloop.sensor_block_t), or unknown")
      .def_readonly("rows", &Channel::rows, "rows: one per event, per tick and axis for blocks")
      .def_readonly("events", &Channel::events, "events on the channel")
      .def_readonly("skipped", &Channel::skipped, "events that did not decode or broke the message contract")
      .def_readonly("columns", &Channel::columns,
                    "name -> numpy array (float64, int64, or object for texts); a variable-length field (a "
                    "status's counters, a trajectory's points) is a list of one array per row")
      .def_readonly("units", &Channel::units, "name -> unit (s, V, m, us, tick, 1 for counts and codes)")
      .def_readonly("descriptions", &Channel::descriptions, "name -> what the column holds")
      .def_readonly("legends", &Channel::legends, "name -> the meaning of its integer codes ('0=off,1=...')")
      .def_readonly("counters", &Channel::counters,
                    "HX_STATUS: counter name -> float64 array, one value per row (NaN where the row's process "
                    "does not report it); filter rows by the 'process' column")
      .def(
          "__getitem__", [](const Channel& c, const std::string& name) { return c.columns[py::str(name)]; },
          py::arg("column"))
      .def("__contains__", [](const Channel& c, const std::string& name) { return c.columns.contains(name); })
      .def("__len__", [](const Channel& c) { return c.rows; })
      .def("keys", [](const Channel& c) { return c.columns.attr("keys")(); })
      .def("__repr__", [](const Channel& c) {
        return "hystloop.Channel(" + c.name + ", " + c.type_name + ", " + std::to_string(c.rows) + " rows, " +
               std::to_string(py::len(c.columns)) + " columns)";
      });

  py::class_<Log>(m, "Log", "an LCM event log read by hystloop.read_log")
      .def_readonly("files", &Log::files, "the files read, in order (one record)")
      .def_readonly("channels", &Log::channels, "channel name -> Channel, in the order of their first events")
      .def_readonly("warnings", &Log::warnings,
                    "what was not read cleanly: damaged or truncated files, events that did not decode")
      .def_readonly("scans", &Log::scans, "per file: bytes, events, skipped_bytes, trailing_bytes")
      .def_readonly("t0_utime_us", &Log::t0_utime_us,
                    "time zero of every t_s [us since the epoch]: the first sensor tick, as hystloop-report")
      .def_readonly("axis", &Log::axis, "the axis read (0 x, 1 y, 2 z), None: every axis")
      .def_readonly("channel_counts", &Log::channel_counts, "events per channel, read or not")
      .def("__getitem__", &channel_of, py::arg("channel"),
           "the channel as logged (HX_SENSOR) or by its suffix after the rig prefix (SENSOR)")
      .def("__contains__",
           [](const Log& l, const std::string& name) {
             return l.channels.contains(name) || l.channels.contains(l.prefix + name);
           })
      .def("__repr__", [](const Log& l) {
        std::string list;
        for (auto item : l.channels) list += (list.empty() ? "" : ", ") + py::str(item.first).cast<std::string>();
        return "hystloop.Log(" + std::to_string(l.files.size()) + " file(s): " + list +
               (l.warnings.empty() ? "" : "; " + std::to_string(l.warnings.size()) + " warning(s)") + ")";
      });

  m.def(
      "read_log",
      [](const py::object& path, std::optional<int> axis, const std::optional<std::vector<std::string>>& channels,
         std::optional<double> from_s, std::optional<double> to_s, const std::string& rig, bool warn,
         const std::optional<std::string>& key_file) {
        std::vector<std::string> paths;
        if (py::isinstance<py::str>(path) || py::hasattr(path, "__fspath__")) {
          paths.push_back(py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>());
        } else {
          for (py::handle p : path) paths.push_back(py::str(py::module_::import("os").attr("fspath")(p)));
        }
        return read_log(paths, axis, channels.value_or(std::vector<std::string>{}), from_s, to_s, rig, warn, key_file);
      },
      py::arg("path"), py::arg("axis") = py::none(), py::arg("channels") = py::none(), py::arg("from_s") = py::none(),
      py::arg("to_s") = py::none(), py::arg("rig") = "HX_", py::arg("warn") = true, py::arg("key_file") = py::none(),
      R"doc(read_log(path, axis=None, channels=None, from_s=None, to_s=None, rig="HX_", warn=True, key_file=None) -> Log

Reads an LCM event log the logger wrote (or several, a rotated recording, as one record) with
hystloop-report's reader: a damaged or truncated file is read up to and around the damage, and
what was not read is said in Log.warnings (and as a RuntimeWarning when warn=True).
  path      a file, or a list of files in recording order
  axis      0 (x), 1 (y) or 2 (z): only that axis's ticks of the blocks; None: every axis the
            blocks carry (a one-axis log has x only)
  channels  channels to read, as logged (HX_SENSOR) or by suffix (SENSOR); None: every channel of the rig
  from_s, to_s  rows with from_s <= t_s <= to_s only [s after the first sensor tick]
  rig       the rig's channel prefix
  key_file  the rig key (auth.key_file): messages on the signed channels whose signature fails (what
            the rig refused) are left out and counted in Log.warnings and Log.scans; without it a
            log its keyed logger marked is read unverified, which Log.warnings says
log["SENSOR"] (HX_SENSOR) has one row per tick and axis: t_s [s] (receive time, back-dated per tick,
after the first sensor tick), seq, axis, u_V, u_ff_V, u_fb_V [V], y_ref_m, y_m [m], flags, ...
and y_true_m [m] when the log has HX_SIM_TRUTH (the simulated stage's true position; NaN where none).
HX_COMMAND: one row per planned tick and axis; HX_SIM_TRUTH: seq, axis, y_true_m, t_s; HX_STATUS:
one row per report, Channel.counters its counters by name. Channel.units names each column's unit.)doc");
}

}  // namespace hystloop::python
