#include "lcm/message_checks.hpp"

#include "lcm/message_storage.hpp"
#include "models/model_set.hpp"

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace hystloop {
namespace {

// Collects the findings of one message: any non-finite value outranks a range failure.
class Findings {
 public:
  void require(bool ok) noexcept { out_of_range_ |= !ok; }
  void finite(double v) noexcept { non_finite_ |= !std::isfinite(v); }
  // A string field carries text: a NUL inside it would be cut when the message is encoded again
  // (found by tests/fuzz/fuzz_messages), so the sender and the next receiver would disagree.
  void text(const std::string& s) noexcept { require(s.find('\0') == std::string::npos); }
  // A tick number small enough that seq + any horizon or block length stays exact and finite.
  void tick(std::int64_t seq) noexcept { require(seq >= 0 && seq <= kMaxTick); }
  // NaN is a documented sentinel ("none"); an infinity never is.
  void finite_or_nan(double v) noexcept { non_finite_ |= std::isinf(v); }
  void within(double v, double lo, double hi) noexcept {
    finite(v);
    require(!std::isfinite(v) || (v >= lo && v <= hi));
  }
  void nan_or_within(double v, double lo, double hi) noexcept {
    finite_or_nan(v);
    require(!std::isfinite(v) || (v >= lo && v <= hi));
  }
  // An element count in [lo, max] that every array holds (`consistent`): true when the arrays may be read.
  bool count(std::int32_t n, std::int32_t lo, std::int32_t max, bool consistent) noexcept {
    const bool ok = n >= lo && n <= max && consistent;
    require(ok);
    return ok;
  }
  Verdict verdict() const noexcept {
    if (non_finite_) return Verdict::kNonFinite;
    return out_of_range_ ? Verdict::kOutOfRange : Verdict::kOk;
  }

 private:
  bool non_finite_ = false;
  bool out_of_range_ = false;
};

constexpr double kHuge = 1.0e300;  // "any finite value"

// Off, an experiment, or an online model's mode (its number in models/model_set.hpp's registry).
bool is_command_mode(std::int8_t mode) noexcept {
  bool model = false;
  OnlineModels::for_each([&]<class D>() { model = model || D::mode == mode; });
  return mode == command_block_t::MODE_OFF || mode == command_block_t::MODE_EXPERIMENT || model;
}

}  // namespace

Verdict check_message(const sensor_block_t& msg) noexcept {
  Findings f;
  f.require(msg.utime >= 0 && msg.buffer_depth_ticks >= 0);
  f.tick(msg.seq);
  f.within(msg.dt_s, 1e-7, 1.0);
  f.require(msg.dt_s > 0.0);
  f.require(msg.n_axes >= 1 && msg.n_axes <= sensor_block_t::MAX_AXES);
  if (f.count(msg.n_ticks, 1, sensor_block_t::MAX_TICKS, arrays_consistent(msg))) {
    for (std::size_t i = 0; i < msg.u_V.size(); ++i) {
      f.within(msg.u_V[i], -kMaxAbsVoltage_V, kMaxAbsVoltage_V);
      f.within(msg.u_ff_V[i], -kMaxAbsVoltage_V, kMaxAbsVoltage_V);
      f.within(msg.u_fb_V[i], -kMaxAbsVoltage_V, kMaxAbsVoltage_V);
      f.nan_or_within(msg.y_ref_m[i], -kMaxAbsPosition_m, kMaxAbsPosition_m);
      f.within(msg.y_m[i], -kMaxAbsPosition_m, kMaxAbsPosition_m);
      f.require(msg.flags[i] >= 0 && (msg.flags[i] & ~kKnownSampleFlags) == 0);
    }
  }
  return f.verdict();
}

Verdict check_message(const sim_truth_t& msg) noexcept {
  Findings f;
  f.require(msg.utime >= 0);
  f.tick(msg.seq);
  f.require(msg.n_axes >= 1 && msg.n_axes <= sim_truth_t::MAX_AXES);
  if (f.count(msg.n_ticks, 1, sim_truth_t::MAX_TICKS, arrays_consistent(msg))) {
    for (const double y : msg.y_true_m) f.within(y, -kMaxAbsPosition_m, kMaxAbsPosition_m);
  }
  return f.verdict();
}

Verdict check_message(const command_block_t& msg) noexcept {
  Findings f;
  f.require(msg.utime >= 0 && msg.sample_seq >= -1 && msg.sample_seq <= kMaxTick);
  f.tick(msg.seq);
  f.require(msg.n_axes >= 1 && msg.n_axes <= command_block_t::MAX_AXES);
  if (f.count(msg.n_ticks, 1, command_block_t::MAX_TICKS, arrays_consistent(msg))) {
    for (std::size_t i = 0; i < msg.u_ff_V.size(); ++i) {
      f.within(msg.u_ff_V[i], -kMaxAbsVoltage_V, kMaxAbsVoltage_V);
      f.nan_or_within(msg.y_ref_m[i], -kMaxAbsPosition_m, kMaxAbsPosition_m);
      f.require(msg.params_version[i] >= 0);
      f.require(is_command_mode(msg.mode[i]));
    }
  }
  return f.verdict();
}

Verdict check_message(const trajectory_t& msg) noexcept {
  Findings f;
  f.require(msg.utime >= 0 && msg.start_utime >= 0 && msg.version >= 1);
  f.require(msg.shape >= trajectory_t::HOLD && msg.shape <= trajectory_t::POINTS);
  f.require(msg.axis >= 0 && msg.axis < kWireAxes);
  f.within(msg.amplitude_m, -kMaxAbsPosition_m, kMaxAbsPosition_m);
  f.within(msg.offset_m, -kMaxAbsPosition_m, kMaxAbsPosition_m);
  f.within(msg.phase_rad, -kHuge, kHuge);
  f.within(msg.blend_s, 0.0, kMaxDuration_s);
  const bool periodic =
      msg.shape == trajectory_t::SINE || msg.shape == trajectory_t::COSINE || msg.shape == trajectory_t::TRIANGLE;
  f.within(msg.frequency_Hz, 0.0, kMaxAbsFrequency_Hz);
  f.require(!periodic || msg.frequency_Hz > 0.0);

  f.require(msg.shape != trajectory_t::POINTS || msg.n_points >= 1);
  if (f.count(msg.n_points, 0, trajectory_t::MAX_POINTS, arrays_consistent(msg))) {
    for (std::size_t i = 0; i < msg.points_t_s.size(); ++i) {
      f.within(msg.points_t_s[i], 0.0, kMaxDuration_s);
      f.within(msg.points_y_m[i], -kMaxAbsPosition_m, kMaxAbsPosition_m);
      f.require(i == 0 || msg.points_t_s[i] > msg.points_t_s[i - 1]);
    }
  }
  return f.verdict();
}

Verdict check_message(const mem_params_t& msg) noexcept {
  Findings f;
  f.require(msg.utime >= 0 && msg.version >= 1 && msg.samples_used >= 0);
  f.require(msg.axis >= 0 && msg.axis < kWireAxes);
  f.text(msg.source);
  f.finite(msg.c1);
  f.within(msg.c2, 0.0, kHuge);
  f.finite(msg.c3);
  // MEM's bounds are its descriptor's, as on HX_MODEL.
  struct {
    double mem_c1, mem_c2, mem_c3;
  } const wire{msg.c1, msg.c2, msg.c3};
  MemDescriptor::check_wire(wire, [&](bool ok) { f.require(ok); });
  f.within(msg.residual_m, 0.0, kMaxAbsPosition_m);
  f.within(msg.window_s, 0.0, kMaxDuration_s);
  return f.verdict();
}

namespace {

// Every online model's wire fields (its descriptor's on_wire), whatever the message's kind: numbers
// finite, PI's arrays as long as their count says (and read only then).
class FiniteWireFields {
 public:
  FiniteWireFields(Findings& f, const model_params_t& msg) noexcept : f_(f), msg_(msg) {}
  void operator()(WireName, const double& wire, const auto&) noexcept { f_.finite(wire); }
  void operator()(WireName, const std::int8_t&, const auto&) noexcept {}  // an enumeration: the kind's own check
  void operator()(WireName, const double (&wire)[8], const auto&) noexcept {
    for (const double v : wire) f_.finite(v);
  }
  void operator()(WireName, const std::int32_t& n, const auto&) noexcept {
    arrays_ok_ = f_.count(n, 0, model_params_t::MAX_OPERATORS, arrays_consistent(msg_));
  }
  void operator()(WireName, const std::vector<double>& wire, const auto&, std::size_t) noexcept {
    if (!arrays_ok_) return;
    for (const double v : wire) f_.finite(v);
  }

 private:
  Findings& f_;
  const model_params_t& msg_;
  bool arrays_ok_ = true;
};

void check_model_fields_finite(Findings& f, const model_params_t& msg) noexcept {
  OnlineModels::for_each([&]<class D>() {
    typename D::Params unused{};  // on_wire pairs each wire field with a parameter; only the wire is read here
    D::on_wire(msg, unused, FiniteWireFields(f, msg));
  });
}

// The kind's own sanity bounds (its descriptor's check_wire) and the stage's.
void check_model_kind(Findings& f, const model_params_t& msg) noexcept {
  if (const auto kind = model_kind_from_int(msg.kind)) {
    OnlineModels::visit(*kind, [&]<class D>() { D::check_wire(msg, [&](bool ok) { f.require(ok); }); });
  }  // unknown: the receiver's own reason (check_message refuses it)
  f.require(msg.stage_kind >= model_params_t::STAGE_UNCHANGED && msg.stage_kind <= model_params_t::STAGE_SECOND_ORDER);
  f.require(msg.stage_order == model_params_t::ORDER_HYSTERESIS_THEN_STAGE ||
            msg.stage_order == model_params_t::ORDER_STAGE_THEN_HYSTERESIS);
  if (msg.stage_kind == model_params_t::STAGE_SECOND_ORDER) {
    // k = omega_n^2 up to a 1 MHz resonance, c within what a physical stage damps.
    f.require(msg.stage_k > 0.0 && msg.stage_k <= 4e13 && msg.stage_c > 0.0 && msg.stage_c <= 1e8);
  }
}

}  // namespace

Verdict check_model_params_envelope(const model_params_t& msg) noexcept {
  Findings f;
  f.require(msg.utime >= 0 && msg.version >= 1 && msg.samples_used >= 0);
  f.require(msg.axis >= 0 && msg.axis < kWireAxes);
  f.text(msg.source);
  f.finite(msg.stage_k);
  f.finite(msg.stage_c);
  check_model_fields_finite(f, msg);
  f.within(msg.residual_m, 0.0, kMaxAbsPosition_m);
  f.nan_or_within(msg.heldout_rms_m, 0.0, kMaxAbsPosition_m);
  f.within(msg.window_s, 0.0, kMaxDuration_s);
  if (f.verdict() == Verdict::kOk) check_model_kind(f, msg);  // the ranges read finite numbers only
  return f.verdict();
}

Verdict check_message(const model_params_t& msg) noexcept {
  const Verdict envelope = check_model_params_envelope(msg);
  if (envelope != Verdict::kOk) return envelope;
  const bool known = msg.format_version == model_params_t::FORMAT_VERSION && model_kind_from_int(msg.kind);
  return known ? Verdict::kOk : Verdict::kOutOfRange;
}

Verdict check_message(const service_status_t& msg) noexcept {
  Findings f;
  f.require(msg.utime >= 0 && msg.start_utime >= 0 && msg.pid > 0 && !msg.process.empty());
  f.text(msg.process);
  f.text(msg.host);
  f.text(msg.detail);
  for (const std::string& name : msg.counter_names) f.text(name);
  f.require(msg.state >= service_status_t::STARTING && msg.state <= service_status_t::STOPPING);
  if (f.count(msg.n_counters, 0, service_status_t::MAX_COUNTERS, arrays_consistent(msg))) {
    for (const std::int64_t value : msg.counter_values) f.require(value >= 0);
  }
  for (const double t : {msg.loop_p50_us, msg.loop_p99_us, msg.loop_max_us, msg.latency_p50_us, msg.latency_p99_us,
                         msg.latency_max_us}) {
    f.nan_or_within(t, 0.0, kHuge);
  }
  f.require(msg.late >= 0 && msg.rejected >= 0);
  return f.verdict();
}

Verdict check_message(const control_t& msg) noexcept {
  Findings f;
  f.require(msg.utime >= 0 && msg.request_id > 0);
  f.text(msg.target);
  f.text(msg.experiment);
  f.require(msg.command >= control_t::SET_MODE && msg.command <= control_t::RELEASE_PARAMS);
  f.require(msg.learning >= control_t::LEARNING_OFF && msg.learning <= control_t::LEARNING_RESET);
  f.require((msg.axis >= 0 && msg.axis < kWireAxes) ||
            (msg.axis == control_t::EVERY_AXIS && msg.command == control_t::SET_GAINS));
  f.require(is_command_mode(msg.mode));
  f.nan_or_within(msg.kp, 0.0, kHuge);  // NaN: keep the gain in force
  f.nan_or_within(msg.ki, 0.0, kHuge);
  f.nan_or_within(msg.kd, 0.0, kHuge);
  f.nan_or_within(msg.notch_hz, 0.0, kHuge);
  f.nan_or_within(msg.notch_q, 0.0, kHuge);
  f.nan_or_within(msg.notch2_hz, 0.0, kHuge);
  f.nan_or_within(msg.notch2_q, 0.0, kHuge);
  f.within(msg.experiment_amplitude_V, -kMaxAbsVoltage_V, kMaxAbsVoltage_V);
  f.within(msg.experiment_offset_V, -kMaxAbsVoltage_V, kMaxAbsVoltage_V);
  f.within(msg.experiment_frequency_Hz, 0.0, kMaxAbsFrequency_Hz);
  f.within(msg.experiment_duration_s, 0.0, kMaxDuration_s);
  if (msg.command == control_t::START_EXPERIMENT) {
    f.require(!msg.experiment.empty() && msg.experiment_amplitude_V > 0.0 && msg.experiment_frequency_Hz > 0.0 &&
              msg.experiment_duration_s > 0.0);
  }
  return f.verdict();
}

Verdict check_message(const scan_t& msg) noexcept {
  Findings f;
  f.require(msg.utime >= 0 && msg.start_utime >= 0 && msg.version >= 1);
  f.require(msg.path == scan_t::RASTER || msg.path == scan_t::LISSAJOUS);
  for (const double c : msg.centre_m) f.within(c, -kMaxAbsPosition_m, kMaxAbsPosition_m);
  f.within(msg.blend_s, 0.0, kMaxDuration_s);
  f.within(msg.width_m, 0.0, kMaxAbsPosition_m);
  f.within(msg.height_m, 0.0, kMaxAbsPosition_m);
  f.within(msg.line_rate_Hz, 0.0, kMaxAbsFrequency_Hz);
  f.within(msg.corner_s, 0.0, kMaxDuration_s);
  f.within(msg.settle_s, 0.0, kMaxDuration_s);
  f.within(msg.duration_s, 0.0, kMaxDuration_s);
  for (int i = 0; i < kWireAxes; ++i) {
    f.within(msg.amplitude_m[i], 0.0, kMaxAbsPosition_m);
    f.within(msg.frequency_Hz[i], 0.0, kMaxAbsFrequency_Hz);
    f.within(msg.phase_rad[i], -kHuge, kHuge);
  }
  if (msg.path == scan_t::RASTER) {
    f.require(msg.fast_axis >= 0 && msg.fast_axis < kWireAxes && msg.slow_axis >= 0 && msg.slow_axis < kWireAxes &&
              msg.fast_axis != msg.slow_axis);
    f.require(msg.slow_mode == scan_t::STEPS || msg.slow_mode == scan_t::RAMP);
    f.require(msg.width_m > 0.0 && msg.line_rate_Hz > 0.0 && msg.lines >= 2 && msg.lines <= 4096);
  } else {
    f.require(msg.duration_s > 0.0);
  }
  return f.verdict();
}

}  // namespace hystloop
