#pragma once
// The bridge's built-in plant: a hysteretic stage plus white sensor noise and an optional
// slow drift of its gain (a warming stage), stepped with time as an argument. The
// bridge service and the in-process loop simulation use the same class, so what the
// tests measure is what the demo runs.

#include <cstdint>
#include <random>
#include <string>

#include "models/banning_stage.hpp"
#include "models/mem.hpp"

namespace hystloop {

enum class PlantKind : std::int8_t {
  kBanning = 0,        // Coleman-Hodgdon + second-order stage, Banning et al. Tables 1-2 (default)
  kRambergOsgood = 1,  // the MEM/Ramberg-Osgood model of Strijbosch et al. (the MEM shape is exact)
};

PlantKind parse_plant_kind(const std::string& name, const std::string& field = "bridge.backend");

struct SimulatedStageConfig {
  PlantKind plant = PlantKind::kBanning;
  BanningStageParams banning{};
  MemParams ramberg_osgood{};
  double noise_rms_m = 1e-9;       // white sensor noise, RMS [m]
  std::uint64_t seed = 1;          // of the noise
  double drift_fraction = 0.0;     // gain change at the end of the drift (0.1 = +10 %)
  double drift_start_s = 0.0;      // loop time the drift starts [s]
  double drift_duration_s = 60.0;  // it grows linearly over this long [s]

  void validate() const;  // throws ParameterError naming the field
};

class SimulatedStage {
 public:
  explicit SimulatedStage(const SimulatedStageConfig& config);

  // Applies u [V] over [t, t + dt] and returns the measured position [m] at its end
  // (true position + noise). Allocation- and throw-free.
  double step(double u_V, double t_s, double dt_s) noexcept;

  double true_position_m() const noexcept { return y_true_; }
  double gain_scale() const noexcept { return scale_; }
  const SimulatedStageConfig& config() const noexcept { return config_; }

 private:
  SimulatedStageConfig config_;
  BanningStage banning_;
  MemModel ramberg_osgood_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_;
  double y_true_ = 0.0;
  double scale_ = 1.0;
};

}  // namespace hystloop
