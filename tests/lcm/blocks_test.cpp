// Blocks of several axes: one tick clock, the axes' values tick-major in every array.
#include "lcm/blocks.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>

#include "lcm/message_checks.hpp"
#include "lcm/message_storage.hpp"
#include "message_fixtures.hpp"

namespace hystloop {
namespace {

// Tick t of axis a: the one-axis fixture's values, told apart per axis.
SensorTick sensor_values(std::int64_t t, int axis) {
  SensorTick s = fixtures::sensor_tick_values(t);
  s.u_V += 10.0 * axis;
  s.y_m += 1e-6 * axis;
  s.flags = axis;  // SATURATED on y, SAFE_STATE on z
  return s;
}

sensor_block_t three_axis_block(std::int64_t seq, int ticks) {
  sensor_block_t b{};
  reserve_storage(b);
  begin_block(b, seq, fixtures::kBaseUtime, 1e-4, 3);
  for (std::int64_t t = seq; t < seq + ticks; ++t) {
    const std::array<SensorTick, 3> axes{sensor_values(t, 0), sensor_values(t, 1), sensor_values(t, 2)};
    EXPECT_TRUE(append_tick(b, axes));
  }
  return b;
}

TEST(Blocks, ThreeAxesRoundTripTickByTickAndAxisByAxis) {
  const sensor_block_t sent = three_axis_block(40, 7);
  EXPECT_EQ(sent.n_ticks, 7);
  EXPECT_EQ(sent.n_axes, 3);
  EXPECT_EQ(sent.n_values, 21);
  EXPECT_EQ(check_message(sent), Verdict::kOk);
  const auto bytes = fixtures::encode(sent);
  sensor_block_t got{};
  ASSERT_EQ(got.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  EXPECT_EQ(ticks_of(got), 7u);
  EXPECT_EQ(axes_of(got), 3u);
  for (std::size_t i = 0; i < 7; ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      const SensorTick want = sensor_values(40 + static_cast<std::int64_t>(i), axis);
      const SensorTick t = sensor_tick(got, i, static_cast<std::size_t>(axis));
      EXPECT_EQ(t.seq, 40 + static_cast<std::int64_t>(i));
      EXPECT_EQ(t.u_V, want.u_V) << i << " " << axis;
      EXPECT_EQ(t.y_m, want.y_m) << i << " " << axis;
      EXPECT_EQ(t.flags, axis);
    }
  }
  // for_each_tick walks x unless told another axis.
  std::int64_t seen = 0;
  for_each_tick(got, [&](const SensorTick& t) { EXPECT_EQ(t.u_V, sensor_values(40 + seen++, 0).u_V); });
  EXPECT_EQ(seen, 7);
  seen = 0;
  for_each_tick(
      got, [&](const SensorTick& t) { EXPECT_EQ(t.u_V, sensor_values(40 + seen++, 2).u_V); }, 2);
  EXPECT_EQ(seen, 7);
  // What three axes cost: the header once, then 44 bytes per tick and axis.
  EXPECT_EQ(sent.getEncodedSize(), 8 + 8 + 8 + 8 + 4 + 4 + 1 + 4 + 7 * 3 * (5 * 8 + 4));
}

TEST(Blocks, ATickOfTheWrongNumberOfAxesIsNotAppended) {
  sensor_block_t b = three_axis_block(0, 2);
  EXPECT_FALSE(append_tick(b, sensor_values(2, 0)));  // one axis into a block of three
  const std::array<SensorTick, 2> two{sensor_values(2, 0), sensor_values(2, 1)};
  EXPECT_FALSE(append_tick(b, two));
  EXPECT_EQ(b.n_ticks, 2);
  EXPECT_EQ(b.n_values, 6);
  EXPECT_EQ(check_message(b), Verdict::kOk);

  command_block_t c{};
  begin_block(c, 0, fixtures::kBaseUtime, -1, 2);
  EXPECT_FALSE(append_tick(c, fixtures::command_tick_values(0)));
  const std::array<CommandTick, 2> xy{fixtures::command_tick_values(0), fixtures::command_tick_values(0)};
  EXPECT_TRUE(append_tick(c, xy));
  EXPECT_EQ(check_message(c), Verdict::kOk);
  EXPECT_EQ(command_tick(c, 0, 1).seq, 0);
}

TEST(Blocks, AnAxisCountOutsideOneToThreeOrValuesThatAreNotTicksTimesAxesAreRefused) {
  for (const std::int8_t bad : {std::int8_t{0}, std::int8_t{4}, std::int8_t{-1}}) {
    sensor_block_t b = three_axis_block(0, 4);
    b.n_axes = bad;
    EXPECT_EQ(check_message(b), Verdict::kOutOfRange) << int{bad};
  }
  sensor_block_t b = three_axis_block(0, 4);
  b.n_axes = 2;  // 12 values read as 6 ticks of two axes: not what n_ticks says
  EXPECT_EQ(check_message(b), Verdict::kOutOfRange);
  b = three_axis_block(0, 4);
  b.n_ticks = 12;  // ... or 12 ticks of three axes
  EXPECT_EQ(check_message(b), Verdict::kOutOfRange);

  command_block_t c = fixtures::command_ticks(0, 5, 0);
  ASSERT_EQ(check_message(c), Verdict::kOk);
  c.n_axes = 0;
  EXPECT_EQ(check_message(c), Verdict::kOutOfRange);
  c.n_axes = 5;
  EXPECT_EQ(check_message(c), Verdict::kOutOfRange);
}

}  // namespace
}  // namespace hystloop
