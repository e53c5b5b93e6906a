// hystloop-compensator's plausibility checks on the deployed configuration: a parameter set on
// HX_PARAMS or HX_MODEL whose gain over the actuator's range leaves [linear.gain / F,
// linear.gain * F] (or with a subnormal parameter) is refused and counted, never swapped in (the
// probe's MEM c2 = 1e300 and c1 = 2.9e-322, a units error of 1000x in every model); the
// configuration's own models and the factor are checked at load; and an identification
// experiment of 10 kV is refused naming the actuator's range.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "compensator/compensator_service.hpp"
#include "lcm/blocks.hpp"
#include "lcm/connection.hpp"
#include "runtime/model_params_message.hpp"

namespace hystloop {
namespace {

constexpr std::int64_t kPublisher = 0x7e1d'0003;
const std::string kConfig = std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/compensator.yaml";

CompensatorSettings deployed() {
  CompensatorSettings s = load_compensator_settings(Config::load_file(kConfig));
  s.control.horizon_ticks = 300;
  s.control.mode = FeedforwardMode::kMem;
  return s;
}

mem_params_t mem_message(double c1, double c2, double c3, std::int32_t version) {
  mem_params_t m{};
  m.version = version;
  m.publisher_id = kPublisher;
  m.c1 = c1;
  m.c2 = c2;
  m.c3 = c3;
  m.valid = 1;
  m.source = "probe";
  return m;
}

model_params_t model_message(const ModelParamSet& set, std::int32_t version) {
  model_params_t m{};
  set_model(m, set);
  m.version = version;
  m.publisher_id = kPublisher;
  m.valid = true;
  m.source = "probe";
  return m;
}

struct Rig {
  std::unique_ptr<lcm::LCM> lcm = open_lcm("memq://");
  ChannelNames channels{};
  CompensatorSettings settings = deployed();
  CompensatorService service{settings, *lcm, channels};
  sensor_block_t block{};

  void run(std::int64_t from, std::int64_t n) {
    for (std::int64_t k = from; k < from + n; k += 10) {
      begin_block(block, k, 1'700'000'000'000'000 + 100 * k, 1e-4);
      for (std::int64_t t = k; t < k + 10; ++t) append_tick(block, SensorTick{0, t, 0.0, 0.0, 0.0, 0.0, 0.0, 0});
      service.on_sensor(block, wall_utime());
    }
  }
  std::uint64_t refused() const { return service.counters().params_refused; }
  std::uint64_t accepted() const { return service.compensator().counters().params_accepted; }
};

TEST(CompensatorPlausibility, TheProbesMemSetsAreRefusedAndNeverSwappedIn) {
  Rig r;
  r.run(0, 20);
  const MemParams in_use = r.service.compensator().mem_params();
  r.service.on_params(mem_message(in_use.c1, 1e300, in_use.c3, 2));
  EXPECT_EQ(r.refused(), 1u);
  r.service.on_params(mem_message(2.9e-322, in_use.c2, in_use.c3, 3));
  EXPECT_EQ(r.refused(), 2u);
  r.service.on_params(mem_message(1e3 * in_use.c1, 1e3 * in_use.c2, in_use.c3, 4));  // y in mm
  EXPECT_EQ(r.refused(), 3u);
  EXPECT_EQ(r.accepted(), 0u);
  r.run(20, 2000);  // reversals pass: nothing was waiting to be swapped in
  EXPECT_EQ(r.service.compensator().counters().params_swapped, 0u);
  EXPECT_EQ(r.service.compensator().mem_params().c2, in_use.c2);

  // A plausible one (the stage 10 % stiffer) from the same publisher is still taken.
  r.service.on_params(mem_message(1.1 * in_use.c1, 1.1 * in_use.c2, in_use.c3, 5));
  EXPECT_EQ(r.refused(), 3u);
  EXPECT_EQ(r.accepted(), 1u);
}

TEST(CompensatorPlausibility, EveryModelWithAGain1000xTooLargeIsRefusedOnTheModelChannel) {
  Rig r;
  r.run(0, 20);
  const CompensatorConfig& c = r.settings.control;
  ModelParamSet linear;
  linear.kind = ModelKind::linear;
  linear.linear = c.models.linear;
  linear.linear.gain *= 1e3;
  ModelParamSet pi;
  pi.kind = ModelKind::pi;
  pi.pi = c.models.pi;
  for (std::size_t i = 0; i < pi.pi.count; ++i) pi.pi.weights[i] *= 1e3;
  ModelParamSet katalenic;
  katalenic.kind = ModelKind::katalenic;
  katalenic.katalenic = c.models.katalenic;
  katalenic.katalenic.output_shaping.gain *= 1e3;
  ModelParamSet mem;
  mem.mem = c.models.mem;
  mem.mem.c1 *= 1e3;
  mem.mem.c2 *= 1e3;
  std::int32_t version = 2;
  for (const ModelParamSet& set : {linear, pi, katalenic, mem}) r.service.on_model(model_message(set, version++));
  EXPECT_EQ(r.refused(), 4u);
  EXPECT_EQ(r.accepted(), 0u);
  // The deployed PI as it is: taken.
  pi.pi = c.models.pi;
  r.service.on_model(model_message(pi, version++));
  EXPECT_EQ(r.refused(), 4u);
  EXPECT_EQ(r.accepted(), 1u);
}

TEST(CompensatorPlausibility, TheBandIsTheConfiguredLinearGainOverTheActuatorsRange) {
  const CompensatorSettings s = deployed();
  const GainPlausibility band = gain_plausibility(s);
  EXPECT_EQ(band.nominal_gain_m_per_V, s.control.models.linear.gain);
  EXPECT_EQ(band.factor, 10.0);
  EXPECT_EQ(band.u_min_V, -250.0);
  EXPECT_EQ(band.u_max_V, 250.0);

  const auto refusal = [](const std::string& yaml) {
    try {
      load_compensator_settings(Config::from_string(yaml, "compensator.yaml"));
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(refusal("compensator: {plausible_gain_factor: 20}"), "accepted");
  EXPECT_NE(refusal("compensator: {plausible_gain_factor: 1}").find("compensator.plausible_gain_factor"),
            std::string::npos);
  // The file's own models: a snippet with y in mm is found at start.
  const std::string mm = refusal("mem: {c1: 1.985e-6, c2: 2.032e-6, c3: 0.2001}");
  EXPECT_NE(mm.find("compensator.yaml: mem.c1"), std::string::npos) << mm;
  EXPECT_NE(refusal("linear: {gain: -6.34e-9}").find("linear.gain"), std::string::npos);
  // ... unless the band is made that wide on purpose.
  EXPECT_EQ(refusal("compensator: {plausible_gain_factor: 1000}\nmem: {c1: 1.985e-8, c2: 2.032e-8, c3: 0.2001}"),
            "accepted");
}

TEST(CompensatorPlausibility, ATenKilovoltExperimentIsRefusedNamingTheActuatorsRange) {
  Rig r;
  r.run(0, 20);
  control_t c{};
  c.request_id = 1;
  c.command = control_t::START_EXPERIMENT;
  c.experiment = "sine";
  c.experiment_amplitude_V = 1e4;
  c.experiment_frequency_Hz = 0.1;  // slow enough for the slew limit: only the range refuses it
  c.experiment_duration_s = 10.0;
  r.service.on_control(c);
  EXPECT_EQ(r.service.counters().control_refused, 1u);
  EXPECT_FALSE(r.service.compensator().experiment_running());
  EXPECT_EQ(r.service.compensator().experiments_queued(), 0u);

  Compensator direct(r.settings.control);
  try {
    direct.start_experiment(make_experiment_spec("sine", 1e4, 0.0, 0.1, 10.0));
    FAIL() << "a 10 kV excitation was queued";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("actuator.u_min_V/u_max_V"), std::string::npos) << e.what();
  }
  // At the range's edge it is taken.
  c.request_id = 2;
  c.experiment_amplitude_V = 250.0;
  r.service.on_control(c);
  EXPECT_EQ(r.service.counters().control_refused, 1u);
  EXPECT_EQ(r.service.counters().control_acted, 1u);
}

}  // namespace
}  // namespace hystloop
