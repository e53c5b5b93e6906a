#pragma once
// The bridge's built-in plant: a hysteretic stage plus white sensor noise and an optional
// slow drift of its gain (a warming stage), stepped with time as an argument. The
// bridge service and the in-process loop simulation use the same class, so what the
// tests measure is what the demo runs.
//
// The series plant is any stage: any hysteresis model of the library (models/hysteresis_plant.hpp),
// then any linear stage with an input delay (models/linear_stage.hpp, sampled exactly once at the
// tick `tick_s`), then the sensor noise. A real stage is rarely Banning's single mode, and a
// compensator is best tested against a plant that is not the model it inverts.

#include <cstdint>
#include <optional>
#include <random>
#include <string>

#include "models/banning_stage.hpp"
#include "models/hysteresis_plant.hpp"
#include "models/linear_stage.hpp"
#include "models/mem.hpp"

namespace hystloop {

enum class PlantKind : std::int8_t {
  kBanning = 0,        // Coleman-Hodgdon + second-order stage, Banning et al. Tables 1-2 (default)
  kRambergOsgood = 1,  // the MEM/Ramberg-Osgood model of Strijbosch et al. (the MEM shape is exact)
  kSeries = 2,         // `hysteresis` then `linear` (with its delay): any model, any stage
};

PlantKind parse_plant_kind(const std::string& name, const std::string& field = "bridge.backend");

struct SimulatedStageConfig {
  PlantKind plant = PlantKind::kBanning;
  BanningStageParams banning{};
  MemParams ramberg_osgood{};
  // The series plant's (used, and validated, only when plant is kSeries). By default Banning's
  // Table 1 hysteresis then Table 2's stage, without delay.
  HysteresisPlantSpec hysteresis{};
  LinearStageSpec linear = LinearStageSpec::second_order(SecondOrderStageParams{}.k, SecondOrderStageParams{}.c);
  // [s] The series plant's tick: `linear` is sampled at it once, at construction (step() is then
  // allocation free). step() with another dt returns NaN: the bridge and the loop simulations set it
  // to their own tick.
  double tick_s = 1e-4;
  double noise_rms_m = 1e-9;       // white sensor noise, RMS [m]
  std::uint64_t seed = 1;          // of the noise
  double drift_fraction = 0.0;     // gain change at the end of the drift (0.1 = +10 %)
  double drift_start_s = 0.0;      // loop time the drift starts [s]
  double drift_duration_s = 60.0;  // it grows linearly over this long [s]

  // Throws ParameterError naming the field; the series plant's as the bridge's keys name them
  // ("plant.hysteresis.bouc_wen.gamma", "plant.stage.poles[1]", "plant.stage.delay_s").
  void validate() const;
};

class SimulatedStage {
 public:
  explicit SimulatedStage(const SimulatedStageConfig& config);

  // Applies u [V] over [t, t + dt] and returns the measured position [m] at its end
  // (true position + noise). Allocation- and throw-free. The series plant returns NaN for a dt
  // other than its tick_s (and for a non-finite u), its state untouched.
  double step(double u_V, double t_s, double dt_s) noexcept;

  double true_position_m() const noexcept { return y_true_; }
  double gain_scale() const noexcept { return scale_; }
  const SimulatedStageConfig& config() const noexcept { return config_; }

 private:
  SimulatedStageConfig config_;
  BanningStage banning_;
  MemModel ramberg_osgood_;
  std::optional<HysteresisPlant> hysteresis_;  // the series plant's (kSeries only)
  std::optional<LinearStageSimulator> linear_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_;
  double y_true_ = 0.0;
  double scale_ = 1.0;
};

}  // namespace hystloop
