// scan_t -> the path it describes: every field lands where the compensator and hystloop-report
// read it (one function serves both), and a path kind it does not know is refused by name.
#include <gtest/gtest.h>

#include <variant>

#include "core/errors.hpp"
#include "lcm/scan_message.hpp"

namespace hystloop {
namespace {

TEST(ScanMessage, ARasterCarriesEveryFieldOfTheMessage) {
  scan_t m{};
  m.path = scan_t::RASTER;
  m.fast_axis = 1;
  m.slow_axis = 0;
  m.width_m = 1e-6;
  m.height_m = 2e-6;
  m.lines = 64;
  m.line_rate_Hz = 50.0;
  m.slow_mode = scan_t::RAMP;
  m.corner_s = 1e-3;
  m.settle_s = 0.02;
  m.centre_m[0] = 1e-7;
  m.centre_m[1] = -2e-7;
  const auto path = scan_path_of(m);
  ASSERT_TRUE(std::holds_alternative<RasterSpec>(path));
  const RasterSpec& r = std::get<RasterSpec>(path);
  EXPECT_EQ(r.fast_axis, 1);
  EXPECT_EQ(r.slow_axis, 0);
  EXPECT_EQ(r.width_m, 1e-6);
  EXPECT_EQ(r.height_m, 2e-6);
  EXPECT_EQ(r.lines, 64);
  EXPECT_EQ(r.line_rate_hz, 50.0);
  EXPECT_EQ(r.slow_mode, SlowMode::kRamp);
  EXPECT_EQ(r.corner_s, 1e-3);
  EXPECT_EQ(r.settle_s, 0.02);
  EXPECT_EQ(r.centre_m[0], 1e-7);
  EXPECT_EQ(r.centre_m[1], -2e-7);
  m.slow_mode = scan_t::STEPS;
  EXPECT_EQ(std::get<RasterSpec>(scan_path_of(m)).slow_mode, SlowMode::kSteps);
}

TEST(ScanMessage, ALissajousFigureCarriesEveryAxis) {
  scan_t m{};
  m.path = scan_t::LISSAJOUS;
  for (int i = 0; i < 3; ++i) {
    m.amplitude_m[i] = (i + 1) * 1e-7;
    m.frequency_Hz[i] = 50.0 - i;
    m.phase_rad[i] = 0.1 * i;
    m.centre_m[i] = -1e-8 * i;
  }
  m.duration_s = 1.5;
  const auto path = scan_path_of(m);
  ASSERT_TRUE(std::holds_alternative<LissajousSpec>(path));
  const LissajousSpec& l = std::get<LissajousSpec>(path);
  for (int i = 0; i < 3; ++i) {
    const auto at = static_cast<std::size_t>(i);
    EXPECT_EQ(l.amplitude_m[at], (i + 1) * 1e-7);
    EXPECT_EQ(l.frequency_hz[at], 50.0 - i);
    EXPECT_EQ(l.phase_rad[at], 0.1 * i);
    EXPECT_EQ(l.centre_m[at], -1e-8 * i);
  }
  EXPECT_EQ(l.duration_s, 1.5);
}

TEST(ScanMessage, AnUnknownPathIsRefusedByName) {
  scan_t m{};
  m.path = 3;
  try {
    scan_path_of(m);
    FAIL() << "path 3 taken";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "scan.path");
  }
}

}  // namespace
}  // namespace hystloop
