#pragma once
// Banning et al.'s stage's description: its parameter table (in banning_descriptor.cpp).
// hystloop-model runs it forward; it is identified offline and has no inverse.

#include <span>
#include <string_view>

#include "models/banning_stage.hpp"
#include "models/param_text.hpp"

namespace hystloop {

struct BanningDescriptor : StoresParams<BanningDescriptor, BanningStageParams> {
  using Forward = BanningStage;
  using Inverse = void;
  static constexpr std::string_view name = "banning";
  static constexpr std::string_view summary =
      "Banning et al. 2001 stage: Coleman-Hodgdon hysteresis + second-order mechanics (Tables 1, 2)";
  static constexpr std::string_view notes =
      "dynamic: u is held from the previous row's t to this row's t (t must increase); "
      "forward only (no inverse)";
  static std::span<const ParamSpec<Settings>> table();
};

}  // namespace hystloop
