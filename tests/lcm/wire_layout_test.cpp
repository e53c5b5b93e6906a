// The length-field walk that runs before lcm-gen's decode: it must agree with the real
// encoding of every type, and refuse every length that decode would trust blindly.
#include "lcm/wire_layout.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <tuple>

#include "hystloop/wire_layout_samples.hpp"
#include "lcm/message_fixtures.hpp"

namespace hystloop {
namespace {

template <class T>
void expect_walk_matches_encoding(const T& msg) {
  const auto bytes = fixtures::encode(msg);
  EXPECT_EQ(walk_wire_layout(wire_layout_of<T>(), bytes.data(), bytes.size()), static_cast<std::int64_t>(bytes.size()))
      << T::getTypeName();
}

void put_be32(std::vector<std::uint8_t>& bytes, std::size_t at, std::int32_t value) {
  const auto u = static_cast<std::uint32_t>(value);
  for (int i = 0; i < 4; ++i) bytes[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(u >> (24 - 8 * i));
}

// The bound on the counts of each type with arrays, written here rather than taken from the
// generated layout, so that a generator picking the wrong constant fails. A new type with arrays
// fails the test below until its bound is added here.
template <class T>
constexpr std::int32_t kBound = 0;
template <>
constexpr std::int32_t kBound<sensor_block_t> = sensor_block_t::MAX_VALUES;
template <>
constexpr std::int32_t kBound<command_block_t> = command_block_t::MAX_VALUES;
template <>
constexpr std::int32_t kBound<trajectory_t> = trajectory_t::MAX_POINTS;
template <>
constexpr std::int32_t kBound<model_params_t> = model_params_t::MAX_OPERATORS;
template <>
constexpr std::int32_t kBound<service_status_t> = service_status_t::MAX_COUNTERS;
template <>
constexpr std::int32_t kBound<sim_truth_t> = sim_truth_t::MAX_VALUES;

// The generated layout of T (cmake/lcm_wire_layouts.py) against lcm-gen's own encoder: a message
// with every count at 0, 1, 7 and the bound, each array that long, walks to exactly its encoded
// size, and every truncation is refused; a count one past the bound, or negative, is refused.
template <class T>
void expect_generated_layout_agrees_with_encoding() {
  SCOPED_TRACE(T::getTypeName());
  const WireLayout layout = wire_layout_of<T>();
  EXPECT_EQ(layout.fingerprint, T::getHash());
  const bool has_count = std::ranges::find(layout.fields, WireField::kCount) != layout.fields.end();
  EXPECT_EQ(has_count, kBound<T> > 0) << "a type with arrays: add its bound to kBound";
  EXPECT_EQ(layout.max_count, kBound<T>);
  for (const std::int32_t count : {0, 1, 7, kBound<T>}) {
    if (count > kBound<T>) continue;
    T msg{};
    wire_samples::fill_wire_sample(msg, count);
    const auto bytes = fixtures::encode(msg);
    ASSERT_EQ(walk_wire_layout(layout, bytes.data(), bytes.size()), msg.getEncodedSize()) << count;
    for (std::size_t n = 0; n < bytes.size() && count <= 7; ++n) {
      EXPECT_EQ(walk_wire_layout(layout, bytes.data(), n), -1) << count << " cut at " << n;
    }
  }
  if (!has_count) return;
  for (const std::int32_t bad : {kBound<T> + 1, -1, -2147483647 - 1}) {
    T msg{};
    wire_samples::fill_wire_sample(msg, bad);
    std::vector<std::uint8_t> bytes(1 << 18);  // not getEncodedSize(): a negative count shrinks it
    const int size = msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    ASSERT_GT(size, 8) << bad;
    EXPECT_EQ(walk_wire_layout(layout, bytes.data(), static_cast<std::size_t>(size)), -1) << bad;
  }
}

template <class... T>
void expect_generated_layouts_agree_with_encoding(std::tuple<T...>* /*types*/) {
  (expect_generated_layout_agrees_with_encoding<T>(), ...);
}

// Every type of lcmtypes/ (WireTypes is generated from the same files: a new type is covered here
// without editing this test).
TEST(WireLayout, TheGeneratedLayoutOfEveryTypeAgreesWithItsEncoding) {
  static_assert(std::tuple_size_v<wire_samples::WireTypes> >= 7);
  expect_generated_layouts_agree_with_encoding(static_cast<wire_samples::WireTypes*>(nullptr));
}

TEST(WireLayout, WalkCoversExactlyTheEncodedBytesOfEveryType) {
  for (std::int64_t k = 0; k < 12; ++k) {  // varying array counts and string lengths
    expect_walk_matches_encoding(fixtures::sensor_block(k));
    expect_walk_matches_encoding(fixtures::command_block(k));
    expect_walk_matches_encoding(fixtures::trajectory(k));
    expect_walk_matches_encoding(fixtures::params(k));
    expect_walk_matches_encoding(fixtures::status(k));
    expect_walk_matches_encoding(fixtures::control(k));
  }
}

TEST(WireLayout, WalkAcceptsTheLargestArraysTheContractAllows) {
  auto traj = fixtures::trajectory(0);
  traj.n_points = trajectory_t::MAX_POINTS;
  traj.points_t_s.assign(trajectory_t::MAX_POINTS, 0.5);
  traj.points_y_m.assign(trajectory_t::MAX_POINTS, 1e-7);
  expect_walk_matches_encoding(traj);

  expect_walk_matches_encoding(fixtures::sensor_ticks(0, sensor_block_t::MAX_TICKS));
  expect_walk_matches_encoding(fixtures::command_ticks(0, command_block_t::MAX_TICKS, 0));

  auto status = fixtures::status(0);
  status.n_counters = service_status_t::MAX_COUNTERS;
  status.counter_names.assign(service_status_t::MAX_COUNTERS, "x");
  status.counter_values.assign(service_status_t::MAX_COUNTERS, 1);
  expect_walk_matches_encoding(status);
}

TEST(WireLayout, EveryTruncationIsRefused) {
  const auto bytes = fixtures::encode(fixtures::status(3));
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    EXPECT_LT(walk_wire_layout(wire_layout_of<service_status_t>(), bytes.data(), n), 0) << n;
  }
}

// trajectory_t's n_points sits after the fingerprint and 9 fixed fields.
constexpr std::size_t kTrajectoryCountOffset = 8 + 8 + 8 + 1 + 4 * 8 + 8 + 8;

TEST(WireLayout, CountsDecodeWouldAllocateForAreRefused) {
  auto bytes = fixtures::encode(fixtures::trajectory(2));
  ASSERT_EQ(bytes[kTrajectoryCountOffset + 3], 3u);  // the offset is right: n_points = 3
  for (const std::int32_t bad : {-1, -2147483647 - 1, 257, 1 << 28, 2147483647}) {
    put_be32(bytes, kTrajectoryCountOffset, bad);
    EXPECT_LT(walk_wire_layout(wire_layout_of<trajectory_t>(), bytes.data(), bytes.size()), 0) << bad;
  }
  put_be32(bytes, kTrajectoryCountOffset, 4);  // within bounds but more than the bytes hold
  EXPECT_LT(walk_wire_layout(wire_layout_of<trajectory_t>(), bytes.data(), bytes.size()), 0);
}

// n_values, the arrays' length, sits after the fingerprint and sensor_block_t's utime, seq, dt_s,
// buffer_depth_ticks, n_ticks and n_axes; after command_block_t's utime, seq, sample_seq, n_ticks
// and n_axes.
constexpr std::size_t kSensorCountOffset = 8 + 8 + 8 + 8 + 4 + 4 + 1;
constexpr std::size_t kCommandCountOffset = 8 + 8 + 8 + 8 + 4 + 1;

// A corrupted value count is refused by the walk, i.e. before decode would resize six
// arrays to it (a negative count or one past MAX_VALUES, or more values than the bytes hold).
template <class T>
void expect_bad_tick_counts_refused(std::vector<std::uint8_t> bytes, std::size_t offset, std::int32_t n_ticks) {
  ASSERT_EQ(bytes[offset + 3], static_cast<std::uint8_t>(n_ticks));  // the offset is right
  ASSERT_EQ(walk_wire_layout(wire_layout_of<T>(), bytes.data(), bytes.size()), static_cast<std::int64_t>(bytes.size()));
  for (const std::int32_t bad : {-1, -2147483647 - 1, T::MAX_VALUES + 1, 1 << 28, 2147483647, n_ticks + 1}) {
    put_be32(bytes, offset, bad);
    EXPECT_LT(walk_wire_layout(wire_layout_of<T>(), bytes.data(), bytes.size()), 0) << T::getTypeName() << " " << bad;
  }
  // Fewer ticks than the arrays hold: the walk ends early, so the sizes disagree.
  put_be32(bytes, offset, n_ticks - 1);
  EXPECT_NE(walk_wire_layout(wire_layout_of<T>(), bytes.data(), bytes.size()), static_cast<std::int64_t>(bytes.size()));
}

TEST(WireLayout, CorruptedTickCountsAreRefusedBeforeDecode) {
  expect_bad_tick_counts_refused<sensor_block_t>(fixtures::encode(fixtures::sensor_ticks(40, 7)), kSensorCountOffset,
                                                 7);
  expect_bad_tick_counts_refused<command_block_t>(fixtures::encode(fixtures::command_ticks(40, 7, 30)),
                                                  kCommandCountOffset, 7);
}

TEST(WireLayout, EveryTruncationOfABlockIsRefused) {
  const auto sensor = fixtures::encode(fixtures::sensor_block(4));
  for (std::size_t n = 0; n < sensor.size(); ++n) {
    EXPECT_LT(walk_wire_layout(wire_layout_of<sensor_block_t>(), sensor.data(), n), 0) << n;
  }
  const auto command = fixtures::encode(fixtures::command_block(4));
  for (std::size_t n = 0; n < command.size(); ++n) {
    EXPECT_LT(walk_wire_layout(wire_layout_of<command_block_t>(), command.data(), n), 0) << n;
  }
}

TEST(WireLayout, StringLengthsDecodeWouldMisreadAreRefused) {
  auto bytes = fixtures::encode(fixtures::params(1));
  const std::size_t string_at = bytes.size() - (4 + fixtures::params(1).source.size() + 1);
  for (const std::int32_t bad : {0, -1, -2147483647 - 1, 2147483647, 1 << 20}) {
    put_be32(bytes, string_at, bad);
    EXPECT_LT(walk_wire_layout(wire_layout_of<mem_params_t>(), bytes.data(), bytes.size()), 0) << bad;
  }
}

TEST(WireLayout, FingerprintIsReadBigEndian) {
  const auto bytes = fixtures::encode(fixtures::sensor_block(0));
  EXPECT_EQ(wire_fingerprint(bytes.data(), bytes.size()), sensor_block_t::getHash());
  EXPECT_EQ(wire_fingerprint(bytes.data(), 7), 0);
  EXPECT_EQ(wire_fingerprint(nullptr, 100), 0);
}

}  // namespace
}  // namespace hystloop
