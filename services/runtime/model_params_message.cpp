#include "runtime/model_params_message.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <type_traits>
#include <utility>
#include <vector>

#include "models/model_descriptors.hpp"

namespace hystloop {
namespace {

static_assert(ShapingFunction::kMaxCoefficients == 8, "model_params_t carries 8 coefficients");
static_assert(kPiMaxOperators == model_params_t::MAX_OPERATORS, "model_params_t carries kPiMaxOperators plays");

using Coefficients = std::array<double, ShapingFunction::kMaxCoefficients>;
using Plays = std::array<double, kPiMaxOperators>;

// The visitors of the descriptors' on_wire (models/model_set.hpp): a parameter onto its
// wire field, a wire field back, a wire field to 0.
struct Write {
  void operator()(WireName, double& wire, double p) const { wire = p; }
  void operator()(WireName, std::int8_t& wire, ShapingKind p) const { wire = static_cast<std::int8_t>(p); }
  void operator()(WireName, double (&wire)[8], const Coefficients& p) const { std::copy(p.begin(), p.end(), wire); }
  void operator()(WireName, std::int32_t& wire, std::size_t count) const {
    wire = static_cast<std::int32_t>(std::min(count, kPiMaxOperators));
  }
  void operator()(WireName, std::vector<double>& wire, const Plays& p, std::size_t count) const {
    wire.assign(p.begin(), p.begin() + static_cast<std::ptrdiff_t>(std::min(count, kPiMaxOperators)));
  }
};

struct Read {
  bool known = true;  // false: a shaping kind this build does not know
  void operator()(WireName, double wire, double& p) const { p = wire; }
  void operator()(WireName, std::int8_t wire, ShapingKind& p) {
    known = known && wire >= model_params_t::SHAPING_LINEAR && wire <= model_params_t::SHAPING_TANH;
    p = static_cast<ShapingKind>(wire);
  }
  void operator()(WireName, const double (&wire)[8], Coefficients& p) const {
    std::copy(std::begin(wire), std::end(wire), p.begin());
  }
  void operator()(WireName, std::int32_t wire, std::size_t& count) const {
    count = std::min(static_cast<std::size_t>(std::max(wire, 0)), kPiMaxOperators);
  }
  void operator()(WireName, const std::vector<double>& wire, Plays& p, std::size_t& count) const {
    count = std::min(count, wire.size());
    std::copy_n(wire.begin(), count, p.begin());
  }
};

struct Clear {
  template <class W, class... P>
  void operator()(WireName, W& wire, const P&...) const {
    if constexpr (std::is_arithmetic_v<W>) {
      wire = 0;
    } else if constexpr (std::is_array_v<W>) {
      std::fill(std::begin(wire), std::end(wire), 0.0);
    } else {
      wire.clear();
    }
  }
};

}  // namespace

void set_model(model_params_t& msg, const ModelParamSet& set) {
  OnlineModels::for_each([&]<class D>() { D::on_wire(msg, std::as_const(set.*D::in_set), Clear{}); });
  msg.format_version = model_params_t::FORMAT_VERSION;
  msg.kind = static_cast<std::int8_t>(set.kind);
  msg.stage_kind = model_params_t::STAGE_UNCHANGED;
  msg.stage_k = msg.stage_c = 0.0;
  msg.stage_order = model_params_t::ORDER_HYSTERESIS_THEN_STAGE;
  // A linear stage of any order is not carried (the message has Banning's k and c): the receiver
  // keeps the stage it has, which a linear one comes from its configuration.
  if (set.stage && !set.stage->is_linear()) {
    msg.stage_kind = set.stage->has_dynamics() ? model_params_t::STAGE_SECOND_ORDER : model_params_t::STAGE_NONE;
    if (set.stage->has_dynamics()) {
      msg.stage_k = set.stage->second_order.k;
      msg.stage_c = set.stage->second_order.c;
    }
    msg.stage_order = set.stage->order == BanningOrder::kStageThenHysteresis
                          ? model_params_t::ORDER_STAGE_THEN_HYSTERESIS
                          : model_params_t::ORDER_HYSTERESIS_THEN_STAGE;
  }
  OnlineModels::visit(set.kind, [&]<class D>() { D::on_wire(msg, set.*D::in_set, Write{}); });
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
  Read read;
  OnlineModels::visit(*kind, [&]<class D>() { D::on_wire(msg, set.*D::in_set, read); });
  if (!read.known) return std::nullopt;
  return set;
}

ModelParamSet model_from_message(const mem_params_t& msg) noexcept {
  ModelParamSet set;
  set.kind = ModelKind::mem;
  set.mem = {msg.c1, msg.c2, msg.c3};
  return set;
}

}  // namespace hystloop
