#include "runtime/stage_config.hpp"

#include <string>

#include "runtime/config_validation.hpp"

namespace hystloop {

StageModel read_stage_model(const Config& config, const StageModel& defaults, double dt_s) {
  StageModel stage = defaults;
  const std::string kind = config.get<std::string>("stage.kind", "none");
  if (kind == "second_order") {
    stage.kind = StageModel::Kind::kSecondOrder;
  } else if (kind == "none") {
    stage.kind = StageModel::Kind::kNone;
    for (const char* key : {"stage.k", "stage.c"}) {
      if (config.has(key)) config.fail("stage.kind", std::string("is none: set it to second_order to use ") + key);
    }
  } else {
    config.fail("stage.kind", "must be none or second_order (got '" + kind + "')");
  }
  stage.second_order.k = config.get_positive("stage.k", stage.second_order.k);
  stage.second_order.c = config.get_positive("stage.c", stage.second_order.c);
  const std::string order = config.get<std::string>("stage.order", "hysteresis_then_stage");
  if (order == "hysteresis_then_stage") {
    stage.order = BanningOrder::kHysteresisThenStage;
  } else if (order == "stage_then_hysteresis") {
    stage.order = BanningOrder::kStageThenHysteresis;
  } else {
    config.fail("stage.order", "must be hysteresis_then_stage or stage_then_hysteresis (got '" + order + "')");
  }
  validate_config_section(config, "", [&] { stage.validate(dt_s); });
  return stage;
}

}  // namespace hystloop
