// Banning et al.'s stage's parameter table.
#include "models/model_descriptors.hpp"

#include <string>

#include "models/param_fields.hpp"

namespace hystloop {

std::span<const ParamSpec<BanningStageParams>> BanningDescriptor::table() {
  using P = BanningStageParams;
  static const ParamSpec<P> rows[] = {
      summarised(number<P>(
          "hysteresis.a", "m/V", "slope of f: loop centres lie on w = a u",
          [](auto& p) -> auto& { return p.hysteresis.a; })),
      summarised(number<P>(
          "hysteresis.b", "m/V", "slope of small loops, a/2 <= b <= a",
          [](auto& p) -> auto& { return p.hysteresis.b; })),
      summarised(number<P>(
          "hysteresis.alpha", "1/V", "relaxation rate onto f after a reversal",
          [](auto& p) -> auto& { return p.hysteresis.alpha; })),
      summarised(number<P>(
          "hysteresis.s_max", "V", "saturation of f and g", [](auto& p) -> auto& { return p.hysteresis.s_max; })),
      summarised(number<P>(
          "stage.k", "1/s^2", "stiffness, omega_n^2", [](auto& p) -> auto& { return p.stage.k; })),
      summarised(number<P>(
          "stage.c", "1/s", "damping, 2 zeta omega_n", [](auto& p) -> auto& { return p.stage.c; })),
      custom<P>(
          "order", "-", "which comes first: hysteresis (the bridge's) or the stage (the paper's)", ValueKind::choice,
          [](P& p, const ParsedValue& v) {
            p.order = v.choice == "stage_then_hysteresis" ? BanningOrder::kStageThenHysteresis
                                                          : BanningOrder::kHysteresisThenStage;
          },
          [](const P& p) {
            return std::string(p.order == BanningOrder::kStageThenHysteresis ? "stage_then_hysteresis"
                                                                             : "hysteresis_then_stage");
          },
          "hysteresis_then_stage|stage_then_hysteresis"),
  };
  return rows;
}

}  // namespace hystloop
