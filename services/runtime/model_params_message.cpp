#include "runtime/model_params_message.hpp"

#include <algorithm>
#include <cstddef>
#include <type_traits>

namespace hystloop {
namespace {

// One shaping function's fields in the message; I8/D const for reading.
template <class I8, class D>
struct ShapingFields {
  I8& kind;
  D& gain;
  D& offset;
  D (&coefficients)[8];
  D& domain_min;
  D& domain_max;
  D& amplitude;
  D& scale;
};
static_assert(ShapingFunction::kMaxCoefficients == 8, "model_params_t carries 8 coefficients");

template <class M, class I8 = std::conditional_t<std::is_const_v<M>, const std::int8_t, std::int8_t>,
          class D = std::conditional_t<std::is_const_v<M>, const double, double>>
ShapingFields<I8, D> in_fields(M& m) {
  return {m.kat_in_shaping,    m.kat_in_gain,       m.kat_in_offset,    m.kat_in_coefficients,
          m.kat_in_domain_min, m.kat_in_domain_max, m.kat_in_amplitude, m.kat_in_scale};
}
template <class M, class I8 = std::conditional_t<std::is_const_v<M>, const std::int8_t, std::int8_t>,
          class D = std::conditional_t<std::is_const_v<M>, const double, double>>
ShapingFields<I8, D> out_fields(M& m) {
  return {m.kat_out_shaping,    m.kat_out_gain,       m.kat_out_offset,    m.kat_out_coefficients,
          m.kat_out_domain_min, m.kat_out_domain_max, m.kat_out_amplitude, m.kat_out_scale};
}

void write_shaping(const ShapingFunction& s, ShapingFields<std::int8_t, double> f) {
  f.kind = static_cast<std::int8_t>(s.kind);
  f.gain = s.gain;
  f.offset = s.offset;
  std::copy(s.coefficients.begin(), s.coefficients.end(), f.coefficients);
  f.domain_min = s.domain_min;
  f.domain_max = s.domain_max;
  f.amplitude = s.amplitude;
  f.scale = s.scale;
}

std::optional<ShapingFunction> read_shaping(ShapingFields<const std::int8_t, const double> f) {
  if (f.kind < model_params_t::SHAPING_LINEAR || f.kind > model_params_t::SHAPING_TANH) return std::nullopt;
  ShapingFunction s;
  s.kind = static_cast<ShapingKind>(f.kind);
  s.gain = f.gain;
  s.offset = f.offset;
  std::copy(std::begin(f.coefficients), std::end(f.coefficients), s.coefficients.begin());
  s.domain_min = f.domain_min;
  s.domain_max = f.domain_max;
  s.amplitude = f.amplitude;
  s.scale = f.scale;
  return s;
}

void clear_parameters(model_params_t& m) {
  m.mem_c1 = m.mem_c2 = m.mem_c3 = 0.0;
  m.linear_gain = m.linear_offset_m = 0.0;
  m.n_operators = 0;
  m.pi_thresholds_V.clear();
  m.pi_weights.clear();
  m.kat_k1 = m.kat_k2 = m.kat_k2_slope = m.kat_k2_domain_min = m.kat_k2_domain_max = m.kat_initial_offset = 0.0;
  write_shaping(ShapingFunction{}, in_fields(m));
  write_shaping(ShapingFunction{}, out_fields(m));
  m.kat_in_gain = m.kat_out_gain = 0.0;
  m.kat_in_domain_min = m.kat_in_domain_max = m.kat_out_domain_min = m.kat_out_domain_max = 0.0;
  m.kat_in_amplitude = m.kat_in_scale = m.kat_out_amplitude = m.kat_out_scale = 0.0;
}

}  // namespace

void set_model(model_params_t& msg, const ModelParamSet& set) {
  clear_parameters(msg);
  msg.format_version = model_params_t::FORMAT_VERSION;
  msg.kind = static_cast<std::int8_t>(set.kind);
  msg.stage_kind = model_params_t::STAGE_UNCHANGED;
  msg.stage_k = msg.stage_c = 0.0;
  msg.stage_order = model_params_t::ORDER_HYSTERESIS_THEN_STAGE;
  if (set.stage) {
    msg.stage_kind = set.stage->has_dynamics() ? model_params_t::STAGE_SECOND_ORDER : model_params_t::STAGE_NONE;
    if (set.stage->has_dynamics()) {
      msg.stage_k = set.stage->second_order.k;
      msg.stage_c = set.stage->second_order.c;
    }
    msg.stage_order = set.stage->order == BanningOrder::kStageThenHysteresis
                          ? model_params_t::ORDER_STAGE_THEN_HYSTERESIS
                          : model_params_t::ORDER_HYSTERESIS_THEN_STAGE;
  }
  switch (set.kind) {
    case ModelKind::mem:
      msg.mem_c1 = set.mem.c1;
      msg.mem_c2 = set.mem.c2;
      msg.mem_c3 = set.mem.c3;
      break;
    case ModelKind::linear:
      msg.linear_gain = set.linear.gain;
      msg.linear_offset_m = set.linear.offset;
      break;
    case ModelKind::pi: {
      const std::size_t n = std::min(set.pi.count, kPiMaxOperators);
      msg.n_operators = static_cast<std::int32_t>(n);
      msg.pi_thresholds_V.assign(set.pi.thresholds.begin(), set.pi.thresholds.begin() + static_cast<std::ptrdiff_t>(n));
      msg.pi_weights.assign(set.pi.weights.begin(), set.pi.weights.begin() + static_cast<std::ptrdiff_t>(n));
      break;
    }
    case ModelKind::katalenic: {
      const KatalenicParams& k = set.katalenic;
      msg.kat_k1 = k.k1;
      msg.kat_k2 = k.k2;
      msg.kat_k2_slope = k.k2_slope;
      msg.kat_k2_domain_min = k.k2_domain_min;
      msg.kat_k2_domain_max = k.k2_domain_max;
      msg.kat_initial_offset = k.initial_offset;
      write_shaping(k.input_shaping, in_fields(msg));
      write_shaping(k.output_shaping, out_fields(msg));
      break;
    }
  }
}

std::optional<ModelParamSet> model_from_message(const model_params_t& msg) {
  if (msg.format_version != model_params_t::FORMAT_VERSION) return std::nullopt;
  const std::optional<ModelKind> kind = model_kind_from_int(msg.kind);
  if (!kind) return std::nullopt;
  ModelParamSet set;
  set.kind = *kind;
  if (msg.stage_kind == model_params_t::STAGE_NONE || msg.stage_kind == model_params_t::STAGE_SECOND_ORDER) {
    StageModel stage;
    if (msg.stage_kind == model_params_t::STAGE_SECOND_ORDER) {
      stage.kind = StageModel::Kind::kSecondOrder;
      stage.second_order = {msg.stage_k, msg.stage_c};
    }
    stage.order = msg.stage_order == model_params_t::ORDER_STAGE_THEN_HYSTERESIS ? BanningOrder::kStageThenHysteresis
                                                                                 : BanningOrder::kHysteresisThenStage;
    set.stage = stage;
  } else if (msg.stage_kind != model_params_t::STAGE_UNCHANGED) {
    return std::nullopt;
  }
  switch (*kind) {
    case ModelKind::mem: set.mem = {msg.mem_c1, msg.mem_c2, msg.mem_c3}; break;
    case ModelKind::linear: set.linear = {msg.linear_gain, msg.linear_offset_m}; break;
    case ModelKind::pi: {
      const std::size_t n = std::min({static_cast<std::size_t>(std::max(msg.n_operators, 0)), kPiMaxOperators,
                                      msg.pi_thresholds_V.size(), msg.pi_weights.size()});
      set.pi.count = n;
      std::copy_n(msg.pi_thresholds_V.begin(), n, set.pi.thresholds.begin());
      std::copy_n(msg.pi_weights.begin(), n, set.pi.weights.begin());
      break;
    }
    case ModelKind::katalenic: {
      KatalenicParams& k = set.katalenic;
      k.k1 = msg.kat_k1;
      k.k2 = msg.kat_k2;
      k.k2_slope = msg.kat_k2_slope;
      k.k2_domain_min = msg.kat_k2_domain_min;
      k.k2_domain_max = msg.kat_k2_domain_max;
      k.initial_offset = msg.kat_initial_offset;
      const auto in = read_shaping(in_fields(msg));
      const auto out = read_shaping(out_fields(msg));
      if (!in || !out) return std::nullopt;
      k.input_shaping = *in;
      k.output_shaping = *out;
      break;
    }
  }
  return set;
}

ModelParamSet model_from_message(const mem_params_t& msg) noexcept {
  ModelParamSet set;
  set.kind = ModelKind::mem;
  set.mem = {msg.c1, msg.c2, msg.c3};
  return set;
}

}  // namespace hystloop
