#pragma once
// Every model's description: the online ones (model_set.hpp's registry) and Banning's stage,
// which hystloop-model runs forward. A descriptor says, as types, the settings struct its parameter
// table writes into, how that becomes the model's parameter struct and back, a one-line summary of
// a set, and the forward and inverse classes (Inverse = void when there is none). hystloop-model's
// registry, hystloop-identify's YAML (ident/params_yaml) and the compensator's model sections all go
// through these, so a parameter is added to a model in its table alone.

#include <span>
#include <string_view>

#include "models/banning_stage.hpp"
#include "models/model_set.hpp"

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

// Every model hystloop-model knows, in the order its --help lists them.
template <class... D>
struct AllModelList {
  template <class F>
  static void for_each(F&& f) {
    (f.template operator()<D>(), ...);
  }
};
template <class... Online>
AllModelList<Online..., BanningDescriptor> with_offline(ModelList<Online...>);
using AllModels = decltype(with_offline(OnlineModels{}));

}  // namespace hystloop
