#include "ident/params_yaml.hpp"

#include "models/model_descriptors.hpp"

namespace hystloop {
namespace {

// The model's section as its table writes it, the same table every reader parses it with.
template <class D>
std::string section(const typename D::Params& p) {
  return yaml_section(D::name, D::table(), D::settings_of(p));
}

bool without_stage(std::string_view name) { return name.rfind("stage.", 0) != 0; }

}  // namespace

std::string to_yaml(const MemParams& p) { return section<MemDescriptor>(p); }
std::string to_yaml(const PiParams& p) { return section<PiDescriptor>(p); }
std::string to_yaml(const LinearParams& p) { return section<LinearDescriptor>(p); }
std::string to_yaml(const KatalenicParams& p) { return section<KatalenicDescriptor>(p); }

std::string to_yaml(const ColemanHodgdonParams& h, const SecondOrderStageParams* stage) {
  BanningStageParams p;
  p.hysteresis = h;
  if (stage != nullptr) p.stage = *stage;
  std::string out =
      yaml_section(BanningDescriptor::name, BanningDescriptor::table(), p, stage != nullptr ? nullptr : &without_stage);
  if (stage != nullptr) {
    // The same stage for the compensator, which inverts it (hystloop-compensator --params FILE
    // reads this section and leaves the bridge's banning section to the bridge). Its keys are the
    // compensator's stage model (runtime/stage_config), not a model's parameter table.
    out += "stage:\n  kind: second_order\n  k: " + format_number(stage->k) +
           "  # [1/s^2]\n  c: " + format_number(stage->c) + "  # [1/s]\n  order: hysteresis_then_stage\n";
  }
  return out;
}

}  // namespace hystloop
