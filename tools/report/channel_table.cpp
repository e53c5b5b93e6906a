#include "channel_table.hpp"

#include <iterator>
#include <stdexcept>
#include <type_traits>
#include <variant>

#include "code_legend.hpp"
#include "decode.hpp"
#include "lcm/blocks.hpp"
#include "log_reader.hpp"
#include "models/model_set.hpp"

namespace hystloop::report {

namespace {

// Appends one row's fields to a table, creating the columns on its first row (or on a
// definition pass, which appends nothing): the column list is written once, where the values are.
class Row {
 public:
  Row(ChannelTable& table, bool define_only) : table_(table), define_only_(define_only) {}

  Row& f(const char* name, const char* unit, double v, const char* description = "") {
    Column& c = column(name, unit, ColumnType::kFloat64, description);
    if (!define_only_) c.f64.push_back(v);
    return *this;
  }
  Row& i(const char* name, const char* unit, std::int64_t v, const char* description = "") {
    Column& c = column(name, unit, ColumnType::kInt64, description);
    if (!define_only_) c.i64.push_back(v);
    return *this;
  }
  // A boolean of the message, as 0/1.
  Row& b(const char* name, bool v) {
    Column& c = column(name, "1", ColumnType::kInt64, "");
    c.legend = "0=false,1=true";
    if (!define_only_) c.i64.push_back(v ? 1 : 0);
    return *this;
  }
  Row& s(const char* name, const std::string& v, const char* description = "") {
    Column& c = column(name, "", ColumnType::kText, description);
    if (!define_only_) c.text.push_back(v);
    return *this;
  }
  // Ragged columns: the row's array, its length in column `count` (or fixed: per_row).
  template <class T>
  Row& ragged(const char* name, const char* unit, const std::vector<T>& values, const char* count,
              std::size_t per_row = 0) {
    constexpr ColumnType type = std::is_floating_point_v<T> ? ColumnType::kFloat64
                                : std::is_integral_v<T>     ? ColumnType::kInt64
                                                            : ColumnType::kText;
    Column& c = column(name, unit, type, "");
    c.count_column = count;
    c.per_row = per_row;
    if (define_only_) return *this;
    for (const auto& v : values) {
      if constexpr (type == ColumnType::kFloat64) {
        c.f64.push_back(v);
      } else if constexpr (type == ColumnType::kInt64) {
        c.i64.push_back(v);
      } else {
        c.text.push_back(v);
      }
    }
    return *this;
  }
  template <std::size_t N>
  Row& fixed(const char* name, const char* unit, const double (&values)[N]) {
    return ragged(name, unit, std::vector<double>(std::begin(values), std::end(values)), "", N);
  }

 private:
  Column& column(const char* name, const char* unit, ColumnType type, const char* description) {
    auto& columns = table_.columns;
    if (index_ == columns.size()) {
      Column c;
      c.name = name;
      c.unit = type == ColumnType::kText ? "" : unit;
      c.description = description;
      c.type = type;
      if (const auto* legend = find_code_legend(table_.type_name, name)) c.legend = legend->text();
      columns.push_back(std::move(c));
    }
    Column& c = columns[index_++];
    if (c.name != name) throw std::logic_error("column order changed: " + c.name + " vs " + name);
    return c;
  }

  ChannelTable& table_;
  bool define_only_;
  std::size_t index_ = 0;
};

constexpr const char* kUtime = "sender's time [us since the UNIX epoch]";

void times(Row& r, double t_s, std::int64_t recv_utime) {
  r.f("t_s", "s", t_s, "receive time after the first sensor tick (hystloop-report's time axis)")
      .i("recv_utime_us", "us", recv_utime, "the event's log timestamp: its receive time [us since the UNIX epoch]");
}

void fields(Row& r, const sensor_block_t& m, const SensorTick& k) {
  r.i("block_utime_us", "us", m.utime, "time of the block's first sample")
      .i("block_seq", "1", m.seq)
      .f("dt_s", "s", m.dt_s, "tick period")
      .i("buffer_depth_ticks", "tick", m.buffer_depth_ticks, "commands buffered ahead when the block was sent")
      .i("utime_us", "us", k.utime, "time of this tick's sample")
      .i("seq", "1", k.seq, "tick number")
      .f("u_V", "V", k.u_V, "voltage applied, after clamping")
      .f("u_ff_V", "V", k.u_ff_V, "feedforward part")
      .f("u_fb_V", "V", k.u_fb_V, "servo correction")
      .f("y_ref_m", "m", k.y_ref_m, "reference; NaN = none")
      .f("y_m", "m", k.y_m, "measured position")
      .i("flags", "1", k.flags);
}

void fields(Row& r, const command_block_t& m, const CommandTick& k) {
  r.i("block_utime_us", "us", m.utime, kUtime)
      .i("block_seq", "1", m.seq)
      .i("sample_seq", "1", m.sample_seq, "last sensor tick the compensator had; -1 = none")
      .i("seq", "1", k.seq, "tick the command is for")
      .f("u_ff_V", "V", k.u_ff_V)
      .f("y_ref_m", "m", k.y_ref_m, "reference; NaN = none")
      .i("params_version", "1", k.params_version, "model version; 0 = none")
      .i("mode", "1", k.mode);
}

void fields(Row& r, const trajectory_t& m) {
  r.i("utime_us", "us", m.utime, kUtime)
      .i("version", "1", m.version)
      .i("shape", "1", m.shape)
      .f("amplitude_m", "m", m.amplitude_m)
      .f("offset_m", "m", m.offset_m)
      .f("frequency_Hz", "Hz", m.frequency_Hz)
      .f("phase_rad", "rad", m.phase_rad)
      .i("start_utime_us", "us", m.start_utime, "loop time of tau = 0; 0 = as received")
      .f("blend_s", "s", m.blend_s)
      .f("corner_s", "s", m.corner_s)
      .i("if_infeasible", "1", m.if_infeasible)
      .i("n_points", "1", m.n_points)
      .ragged("points_t_s", "s", m.points_t_s, "n_points")
      .ragged("points_y_m", "m", m.points_y_m, "n_points");
}

void fields(Row& r, const mem_params_t& m) {
  r.i("utime_us", "us", m.utime, kUtime)
      .i("version", "1", m.version)
      .i("publisher_id", "1", m.publisher_id)
      .f("c1_m_per_V", "m/V", m.c1, "MEM slope at a branch point")
      .f("c2_m_per_V_pow_1_plus_c3", "m/V^(1+c3)", m.c2)
      .f("c3", "1", m.c3)
      .f("residual_m", "m", m.residual_m)
      .i("samples_used", "1", m.samples_used)
      .f("window_s", "s", m.window_s)
      .b("valid", m.valid != 0)
      .s("source", m.source);
}

// Every online model's fields as its descriptor's on_wire names them (models/model_set.hpp), so a
// model or a parameter added there is exported without a line here.
class ModelColumns {
 public:
  explicit ModelColumns(Row& r) : r_(r) {}
  void operator()(WireName w, double v, const auto&) { r_.f(w.name, w.unit, v, w.note); }
  void operator()(WireName w, std::int8_t v, const auto&) { r_.i(w.name, w.unit, v, w.note); }
  void operator()(WireName w, const double (&v)[8], const auto&) { r_.fixed(w.name, w.unit, v); }
  void operator()(WireName w, std::int32_t count, const auto&) {
    r_.i(w.name, w.unit, count, w.note);
    count_name_ = w.name;
  }
  void operator()(WireName w, const std::vector<double>& v, const auto&, std::size_t) {
    r_.ragged(w.name, w.unit, v, count_name_);
  }

 private:
  Row& r_;
  const char* count_name_ = "";
};

void fields(Row& r, const model_params_t& m) {
  r.i("format_version", "1", m.format_version)
      .i("utime_us", "us", m.utime, kUtime)
      .i("version", "1", m.version)
      .i("publisher_id", "1", m.publisher_id)
      .i("kind", "1", m.kind);
  OnlineModels::for_each([&]<class D>() {
    const typename D::Params unused{};  // on_wire pairs each wire field with a parameter; only the wire is read
    D::on_wire(m, unused, ModelColumns(r));
  });
  r.f("residual_m", "m", m.residual_m)
      .f("heldout_rms_m", "m", m.heldout_rms_m, "NaN = not ranked")
      .i("samples_used", "1", m.samples_used)
      .f("window_s", "s", m.window_s)
      .b("valid", m.valid != 0)
      .i("stage_kind", "1", m.stage_kind)
      .f("stage_k", "1/s^2", m.stage_k)
      .f("stage_c", "1/s", m.stage_c)
      .i("stage_order", "1", m.stage_order)
      .s("source", m.source);
}

void fields(Row& r, const service_status_t& m) {
  r.i("utime_us", "us", m.utime, kUtime)
      .s("process", m.process)
      .s("host", m.host)
      .i("pid", "1", m.pid)
      .i("state", "1", m.state)
      .s("detail", m.detail)
      .i("start_utime_us", "us", m.start_utime, "process start [us since the UNIX epoch]")
      .f("loop_p50_us", "us", m.loop_p50_us)
      .f("loop_p99_us", "us", m.loop_p99_us)
      .f("loop_max_us", "us", m.loop_max_us)
      .f("latency_p50_us", "us", m.latency_p50_us)
      .f("latency_p99_us", "us", m.latency_p99_us)
      .f("latency_max_us", "us", m.latency_max_us)
      .i("late", "tick", m.late)
      .i("rejected", "1", m.rejected)
      .i("n_counters", "1", m.n_counters)
      .ragged("counter_names", "", m.counter_names, "n_counters")
      .ragged("counter_values", "1", m.counter_values, "n_counters");
}

void fields(Row& r, const control_t& m) {
  r.i("utime_us", "us", m.utime, kUtime)
      .i("request_id", "1", m.request_id)
      .i("command", "1", m.command)
      .s("target", m.target, "addressee; empty = every process")
      .i("mode", "1", m.mode)
      .f("kp", "1", m.kp)
      .f("ki_per_s", "1/s", m.ki)
      .f("kd_s", "s", m.kd)
      .f("notch_Hz", "Hz", m.notch_hz, "0 = no notch")
      .f("notch_q", "1", m.notch_q)
      .f("notch2_Hz", "Hz", m.notch2_hz, "second notch; 0 = none")
      .f("notch2_q", "1", m.notch2_q)
      .s("experiment", m.experiment)
      .f("experiment_amplitude_V", "V", m.experiment_amplitude_V)
      .f("experiment_offset_V", "V", m.experiment_offset_V)
      .f("experiment_frequency_Hz", "Hz", m.experiment_frequency_Hz)
      .f("experiment_duration_s", "s", m.experiment_duration_s)
      .i("learning", "1", m.learning);
}

// A message of no known type: its size only.
struct Undecoded {
  std::int64_t size_bytes = 0;
};

void fields(Row& r, const Undecoded& m) { r.i("size_bytes", "byte", m.size_bytes); }

// The block messages, whose rows are their ticks, and their tick types.
template <class M>
constexpr bool kBlock = std::is_same_v<M, sensor_block_t> || std::is_same_v<M, command_block_t>;
template <class M>
using TickOf = std::conditional_t<std::is_same_v<M, sensor_block_t>, SensorTick, CommandTick>;

// The message a channel's events decode into, of the type its first event's fingerprint names
// (any channel name, any rig prefix); Undecoded when it is none of the contract's types.
using Message = std::variant<Undecoded, sensor_block_t, command_block_t, trajectory_t, mem_params_t, model_params_t,
                             service_status_t, control_t>;

template <std::size_t I = 1>
Message message_of(const lcm::LogEvent& event) {
  if constexpr (I == std::variant_size_v<Message>) {
    return Undecoded{};
  } else {
    if (has_fingerprint_of<std::variant_alternative_t<I, Message>>(event)) return Message(std::in_place_index<I>);
    return message_of<I + 1>(event);
  }
}

}  // namespace

std::size_t Column::size() const noexcept {
  switch (type) {
    case ColumnType::kFloat64: return f64.size();
    case ColumnType::kInt64: return i64.size();
    default: return text.size();
  }
}

const Column* ChannelTable::find(const std::string& name) const noexcept {
  for (const Column& c : columns) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

void ChannelTable::clear_rows() noexcept {
  for (Column& c : columns) {
    c.f64.clear();
    c.i64.clear();
    c.text.clear();
  }
  rows = 0;
}

struct TableBuilder::Impl {
  std::function<bool(const std::string&)> wanted;
  std::map<std::string, std::uint64_t> counts;
  std::map<std::string, std::size_t> index;  // wanted channel -> position in tables and kinds
  std::vector<ChannelTable> tables;
  std::vector<Message> messages;  // each table's, reused from event to event
  std::int64_t t0_utime = 0;
  double lower_s = 0.0, upper_s = 0.0;
  std::size_t axis = 0;  // the axis of a block's ticks that make its rows

  double t_of(std::int64_t utime) const { return static_cast<double>(utime - t0_utime) * 1e-6; }
  bool in_range(double t) const { return t >= lower_s && t <= upper_s; }

  // The type name and columns of a channel, from an empty message (a block's per-tick fields from an empty tick).
  static void define(ChannelTable& t, const Message& message) {
    std::visit(
        [&](const auto& m) {
          using M = std::decay_t<decltype(m)>;
          if constexpr (!std::is_same_v<M, Undecoded>) t.type_name = std::string("hystloop.") + M::getTypeName();
          Row r(t, true);
          times(r, 0.0, 0);
          if constexpr (kBlock<M>) {
            fields(r, M{}, TickOf<M>{});
          } else {
            fields(r, M{});
          }
        },
        message);
  }

  // false: the event did not decode.
  bool add(ChannelTable& t, Message& message, const lcm::LogEvent& e) {
    const double event_t = t_of(e.timestamp);
    auto row = [&](double row_t, auto&& fields_of) {
      if (!in_range(row_t)) return;
      Row r(t, false);
      times(r, row_t, e.timestamp);
      fields_of(r);
      ++t.rows;
    };
    return std::visit(
        [&](auto& m) {
          using M = std::decay_t<decltype(m)>;
          if constexpr (std::is_same_v<M, Undecoded>) {
            m.size_bytes = e.datalen;
          } else if (!decode_checked(e, m)) {
            return false;
          }
          if constexpr (!kBlock<M>) {
            row(event_t, [&](Row& r) { fields(r, m); });
          } else if (axis < axes_of(m)) {  // a block without the axis has no row of it
            std::size_t i = 0;
            for_each_tick(
                m,
                [&](const auto& k) {
                  // A sensor tick is dated as the report's time axis dates it, a command tick by its block's arrival.
                  double tick_t = event_t;
                  if constexpr (std::is_same_v<M, sensor_block_t>) {
                    tick_t = t_of(tick_recv_utime(e.timestamp, m.n_ticks, i++, m.dt_s));
                  }
                  row(tick_t, [&](Row& r) { fields(r, m, k); });
                },
                axis);
          }
          return true;
        },
        message);
  }
};

TableBuilder::TableBuilder(std::function<bool(const std::string&)> wanted, std::int64_t t0_utime, double lower_s,
                           double upper_s, int axis)
    : impl_(std::make_unique<Impl>()) {
  impl_->wanted = std::move(wanted);
  impl_->t0_utime = t0_utime;
  impl_->lower_s = lower_s;
  impl_->upper_s = upper_s;
  impl_->axis = static_cast<std::size_t>(axis);
}

TableBuilder::~TableBuilder() = default;

ChannelTable* TableBuilder::add(const lcm::LogEvent& event) {
  auto [count, first] = impl_->counts.try_emplace(event.channel, 0);
  ++count->second;
  if (first && impl_->wanted(event.channel)) {  // the first event decides the channel's type and columns
    ChannelTable t;
    t.channel = event.channel;
    impl_->messages.push_back(message_of(event));
    Impl::define(t, impl_->messages.back());
    impl_->index[event.channel] = impl_->tables.size();
    impl_->tables.push_back(std::move(t));
  }
  const auto it = impl_->index.find(event.channel);
  if (it == impl_->index.end()) return nullptr;
  ChannelTable& t = impl_->tables[it->second];
  ++t.events;
  if (!impl_->add(t, impl_->messages[it->second], event)) ++t.skipped;
  return &t;
}

const std::map<std::string, std::uint64_t>& TableBuilder::channel_counts() const noexcept { return impl_->counts; }

std::vector<ChannelTable> TableBuilder::take() {
  std::vector<ChannelTable> tables = std::move(impl_->tables);
  impl_->tables.clear();
  impl_->messages.clear();
  impl_->index.clear();
  return tables;
}

}  // namespace hystloop::report
