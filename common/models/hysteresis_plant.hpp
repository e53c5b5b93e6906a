#pragma once
// Any forward hysteresis model of the library run as a plant, voltage u [V] -> displacement y [m]:
// Coleman–Hodgdon (Banning et al. 2001, Table 1 by default), MEM (Strijbosch, Tiels & Oomen),
// Prandtl–Ishlinskii, Katalenic, Bouc–Wen, or the linear spring. WHY: a simulator tests a
// compensator against a plant that is NOT the model it inverts (a MEM feedforward on a Bouc–Wen
// plant, ...); one value type lets it choose the plant by name from its configuration.
//
// Value type: the models sit in a std::variant and step() dispatches with std::visit, so there is
// no virtual call and no allocation per step (the variant holds each model by value; none of them
// allocates). Every one of these models is rate independent (their steps take no dt), so
// step(u, dt) only checks dt: it is there for the interface the simulator chains with a linear
// stage model (which does need it). The plant is kept independent of that stage.
//
// step(u, dt) returns exactly what the underlying model's forward(u) returns, bit for bit
// (tests/models/hysteresis_plant_test.cpp checks it for every kind). Per-sample calls are noexcept
// and allocation free; a non-finite u or a dt that is not finite and > 0 returns NaN and leaves
// the state untouched.

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

#include "models/bouc_wen.hpp"
#include "models/coleman_hodgdon.hpp"
#include "models/katalenic.hpp"
#include "models/linear.hpp"
#include "models/mem.hpp"
#include "models/prandtl_ishlinskii.hpp"

namespace hystloop {

enum class HysteresisPlantKind { coleman_hodgdon, mem, pi, katalenic, bouc_wen, linear };

// The names, in the enum's order: "coleman_hodgdon", "mem", "pi", "katalenic", "bouc_wen", "linear".
inline constexpr std::array<std::string_view, 6> kHysteresisPlantKindNames = {"coleman_hodgdon", "mem",      "pi",
                                                                              "katalenic",       "bouc_wen", "linear"};

std::string_view to_string(HysteresisPlantKind kind) noexcept;
// One of kHysteresisPlantKindNames; nullopt for anything else.
std::optional<HysteresisPlantKind> parse_hysteresis_plant_kind(std::string_view name) noexcept;
// As parse_hysteresis_plant_kind, but an unknown name throws ParameterError naming `field` and
// listing the accepted names ("kind: unknown hysteresis plant 'x'; expected coleman_hodgdon, mem, ...").
HysteresisPlantKind hysteresis_plant_kind_from_name(std::string_view name, std::string_view field = "kind");

// The project's PI baseline: 15 plays over +-250 V with weights matched to MemParams::paper_like().
PiParams default_plant_pi_params();

struct HysteresisPlantSpec {
  HysteresisPlantKind kind = HysteresisPlantKind::coleman_hodgdon;
  // Only the member `kind` names is used (and validated); the others keep their defaults.
  ColemanHodgdonParams coleman_hodgdon{};  // Banning et al. (2001) Table 1
  MemParams mem{};                         // MemParams::paper_like()
  double mem_reversal_deadband_V = 0.0;    // [V] >= 0, MemModel's; 0 is the paper's model
  PiParams pi = default_plant_pi_params();
  KatalenicParams katalenic{};
  BoucWenParams bouc_wen{};
  LinearParams linear{};

  // Defaults for `name` (one of kHysteresisPlantKindNames); an unknown name throws ParameterError
  // naming "kind" with the accepted names.
  static HysteresisPlantSpec named(std::string_view name);

  // Validates the member `kind` names; throws ParameterError naming the field with its member's
  // prefix ("bouc_wen.gamma", "pi.weights[3]", "mem_reversal_deadband_V").
  void validate() const;
};

// u [V] -> y [m].
class HysteresisPlant {
 public:
  using Model = std::variant<ColemanHodgdon, MemModel, PiModel, KatalenicModel, BoucWen, LinearModel>;

  explicit HysteresisPlant(const HysteresisPlantSpec& spec = {});  // validates

  // Each model's own reset(u0) (a non-finite u0 is taken as 0): Coleman–Hodgdon on its centre line
  // w = f(u0), MEM on its skeleton, PI demagnetised then moved to u0, Katalenic with its
  // initial_offset, Bouc–Wen demagnetised (h = 0), linear at gain u0 + offset.
  void reset(double u0_V = 0.0) noexcept;
  // u held over dt [s] (> 0); returns y [m] at its end: the model's forward(u_V).
  double step(double u_V, double dt_s) noexcept;

  HysteresisPlantKind kind() const noexcept { return spec_.kind; }
  const HysteresisPlantSpec& spec() const noexcept { return spec_; }
  const Model& model() const noexcept { return model_; }
  double input() const noexcept { return u_; }   // last u [V]
  double output() const noexcept { return y_; }  // last y [m]

 private:
  static Model make_model(const HysteresisPlantSpec& spec);

  HysteresisPlantSpec spec_;
  Model model_;
  double u_ = 0.0;
  double y_ = 0.0;
};

}  // namespace hystloop
