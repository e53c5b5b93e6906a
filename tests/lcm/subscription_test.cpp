// Subscription<T> over the in-process memq:// provider: what arrives intact is delivered,
// everything else is rejected, counted by reason, and never crashes (this also runs under
// ASan+UBSan).
#include "lcm/subscription.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "lcm/connection.hpp"
#include "lcm/message_fixtures.hpp"
#include "lcm/publisher.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using namespace std::chrono_literals;

class SubscriptionTest : public ::testing::Test {
 protected:
  lcm::LCM lcm_{"memq://"};

  void publish_raw(const std::string& channel, const std::vector<std::uint8_t>& bytes) {
    ASSERT_EQ(lcm_.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size())), 0);
  }
  int drain() { return handle_pending(lcm_, 0us); }
};

TEST_F(SubscriptionTest, DeliversEachTypeIntactThroughLcm) {
  std::vector<std::int64_t> seqs;
  Subscription<sensor_block_t> sensor(lcm_, "HX_SENSOR",
                                      [&](const sensor_block_t& m, std::int64_t) { seqs.push_back(m.seq); });
  Subscription<trajectory_t> traj(lcm_, "HX_TRAJECTORY");
  Subscription<service_status_t> status(lcm_, "HX_STATUS");
  Publisher<sensor_block_t> pub_sensor(lcm_, "HX_SENSOR");
  Publisher<trajectory_t> pub_traj(lcm_, "HX_TRAJECTORY");
  Publisher<service_status_t> pub_status(lcm_, "HX_STATUS");

  for (std::int64_t k = 0; k < 5; ++k) ASSERT_TRUE(pub_sensor.publish(fixtures::sensor_block(k)));
  ASSERT_TRUE(pub_traj.publish(fixtures::trajectory(4)));
  ASSERT_TRUE(pub_status.publish(fixtures::status(3)));
  EXPECT_EQ(drain(), 7);

  EXPECT_EQ(seqs, (std::vector<std::int64_t>{0, 10, 20, 30, 40}));
  EXPECT_EQ(sensor.counters().accepted, 5u);
  EXPECT_EQ(sensor.counters().rejected_total(), 0u);
  EXPECT_EQ(fixtures::encode(sensor.latest()), fixtures::encode(fixtures::sensor_block(4)));
  EXPECT_EQ(fixtures::encode(traj.latest()), fixtures::encode(fixtures::trajectory(4)));
  EXPECT_EQ(fixtures::encode(status.latest()), fixtures::encode(fixtures::status(3)));
}

TEST_F(SubscriptionTest, EveryTruncationIsRejectedAndCounted) {
  Subscription<service_status_t> status(lcm_, "HX_STATUS");
  Subscription<command_block_t> command(lcm_, "HX_COMMAND");
  const auto status_bytes = fixtures::encode(fixtures::status(4));
  const auto command_bytes = fixtures::encode(fixtures::command_block(4));
  for (std::size_t n = 0; n < status_bytes.size(); ++n) {
    status.receive(status_bytes.data(), n, 0);
  }
  for (std::size_t n = 0; n < command_bytes.size(); ++n) {
    publish_raw("HX_COMMAND", {command_bytes.begin(), command_bytes.begin() + static_cast<long>(n)});
  }
  drain();
  EXPECT_EQ(status.counters().rejected(RejectReason::kDecodeFailed), status_bytes.size());
  EXPECT_EQ(command.counters().rejected(RejectReason::kDecodeFailed), command_bytes.size());
  EXPECT_EQ(status.counters().accepted + command.counters().accepted, 0u);
  EXPECT_EQ(status.valid_count(), 0u);
}

// lcm-gen's decode leaves a primitive array untouched when its count is 0: decoding into a
// reused message must not keep the previous message's elements.
TEST_F(SubscriptionTest, AnEmptyArrayAfterAFullOneDecodesEmpty) {
  Subscription<service_status_t> status(lcm_, "HX_STATUS");
  Subscription<trajectory_t> traj(lcm_, "HX_TRAJECTORY");
  for (std::int64_t k : {4, 5, 4, 5, 5}) {  // status(5) has no counters
    const auto bytes = fixtures::encode(fixtures::status(k));
    status.receive(bytes.data(), bytes.size(), 0);
    EXPECT_EQ(fixtures::encode(status.latest()), bytes) << k;
  }
  EXPECT_EQ(status.counters().accepted, 5u);
  auto empty = fixtures::trajectory(1);
  empty.shape = trajectory_t::SINE;
  empty.n_points = 0;
  empty.points_t_s.clear();
  empty.points_y_m.clear();
  for (const auto& m : {fixtures::trajectory(5), empty, fixtures::trajectory(5), empty}) {
    const auto bytes = fixtures::encode(m);
    traj.receive(bytes.data(), bytes.size(), 0);
    EXPECT_EQ(fixtures::encode(traj.latest()), bytes);
  }
  EXPECT_EQ(traj.counters().accepted, 4u);
}

TEST_F(SubscriptionTest, TrailingBytesAreASizeMismatch) {
  Subscription<sensor_block_t> sensor(lcm_, "HX_SENSOR");
  auto bytes = fixtures::encode(fixtures::sensor_block(1));
  bytes.push_back(0);
  publish_raw("HX_SENSOR", bytes);
  drain();
  EXPECT_EQ(sensor.counters().rejected(RejectReason::kSizeMismatch), 1u);
  EXPECT_EQ(sensor.counters().accepted, 0u);
}

TEST_F(SubscriptionTest, AnotherTypeOnTheChannelIsAWrongType) {
  Subscription<sensor_block_t> sensor(lcm_, "HX_SENSOR");
  publish_raw("HX_SENSOR", fixtures::encode(fixtures::command_block(1)));  // a block too: a plausible size
  drain();
  EXPECT_EQ(sensor.counters().rejected(RejectReason::kWrongType), 1u);
}

TEST_F(SubscriptionTest, InvalidValuesAreRejectedPerReasonAndKeepTheLastGoodMessage) {
  Subscription<command_block_t> command(lcm_, "HX_COMMAND");
  Publisher<command_block_t> unchecked(lcm_, "HX_COMMAND", nullptr);
  ASSERT_TRUE(unchecked.publish(fixtures::command_block(1)));
  auto bad = fixtures::command_block(2);
  bad.u_ff_V.back() = std::numeric_limits<double>::quiet_NaN();
  ASSERT_TRUE(unchecked.publish(bad));
  bad.u_ff_V.back() = std::numeric_limits<double>::infinity();
  ASSERT_TRUE(unchecked.publish(bad));
  bad = fixtures::command_block(3);
  bad.mode.back() = 42;
  ASSERT_TRUE(unchecked.publish(bad));
  drain();
  const auto& c = command.counters();
  EXPECT_EQ(c.received, 4u);
  EXPECT_EQ(c.accepted, 1u);
  EXPECT_EQ(c.rejected(RejectReason::kNonFinite), 2u);
  EXPECT_EQ(c.rejected(RejectReason::kOutOfRange), 1u);
  EXPECT_EQ(command.latest().seq, fixtures::command_block(1).seq);
}

TEST_F(SubscriptionTest, ACustomCheckReplacesTheDefault) {
  Subscription<sensor_block_t>::Options options;
  options.check = [](const sensor_block_t& m) noexcept {
    return m.seq % 20 == 0 ? Verdict::kOk : Verdict::kOutOfRange;  // even rounds
  };
  Subscription<sensor_block_t> even(lcm_, "HX_SENSOR", {}, options);
  Publisher<sensor_block_t> pub(lcm_, "HX_SENSOR");
  for (std::int64_t k = 0; k < 6; ++k) pub.publish(fixtures::sensor_block(k));
  drain();
  EXPECT_EQ(even.counters().accepted, 3u);
  EXPECT_EQ(even.counters().rejected(RejectReason::kOutOfRange), 3u);
}

TEST_F(SubscriptionTest, AThrowingHandlerIsCountedAndLcmCarriesOn) {
  std::vector<RejectReason> reported;
  Subscription<sensor_block_t>::Options options;
  options.on_reject = [&](RejectReason r) { reported.push_back(r); };
  int calls = 0;
  Subscription<sensor_block_t> sensor(
      lcm_, "HX_SENSOR",
      [&](const sensor_block_t& m, std::int64_t) {
        ++calls;
        if (m.seq == 10) throw std::runtime_error("handler bug");
      },
      options);
  Publisher<sensor_block_t> pub(lcm_, "HX_SENSOR");
  for (std::int64_t k = 0; k < 3; ++k) pub.publish(fixtures::sensor_block(k));
  EXPECT_EQ(drain(), 3);
  EXPECT_EQ(calls, 3);
  EXPECT_EQ(sensor.counters().accepted, 2u);
  EXPECT_EQ(sensor.counters().rejected(RejectReason::kHandlerFailed), 1u);
  EXPECT_EQ(sensor.valid_count(), 3u);
  EXPECT_EQ(reported, std::vector<RejectReason>{RejectReason::kHandlerFailed});
}

// Seeded random corruption of every type: flipped bits, overwritten bytes, cut or grown
// buffers. Every message is either accepted (and then valid) or counted as rejected.
template <class T>
void fuzz(const std::vector<T>& originals, std::uint64_t seed, int rounds) {
  lcm::LCM lcm("memq://");
  Subscription<T> sub(lcm, "FUZZ");
  std::mt19937_64 rng(seed);
  for (int i = 0; i < rounds; ++i) {
    auto bytes = fixtures::encode(originals[static_cast<std::size_t>(i) % originals.size()]);
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      const std::size_t at = 8 + rng() % (bytes.size() - 8);  // keep the fingerprint most of the time
      switch (rng() % 4) {
        case 0: bytes[at] ^= static_cast<std::uint8_t>(1u << (rng() % 8)); break;
        case 1: bytes[at] = static_cast<std::uint8_t>(rng()); break;
        case 2: bytes[at] = 0xff; break;
        default: bytes.resize(8 + rng() % (bytes.size() - 7)); break;
      }
      if (bytes.size() <= 8) break;
    }
    if (rng() % 16 == 0) bytes[rng() % 8] ^= 1;  // and sometimes the fingerprint
    sub.receive(bytes.data(), bytes.size(), 0);
    if (sub.valid_count() > 0) {
      ASSERT_EQ(check_message(sub.latest()), Verdict::kOk);
    }
  }
  const auto& c = sub.counters();
  EXPECT_EQ(c.received, static_cast<std::uint64_t>(rounds));
  EXPECT_EQ(c.accepted + c.rejected_total(), c.received);
  EXPECT_GT(c.rejected_total(), 0u);
}

#ifdef __SANITIZE_ADDRESS__
constexpr int kFuzzRounds = 3000;
#else
constexpr int kFuzzRounds = 20000;
#endif

template <class T>
std::vector<T> originals(T (*make)(std::int64_t)) {
  std::vector<T> out;
  for (std::int64_t k = 0; k < 8; ++k) out.push_back(make(k));
  return out;
}

TEST(SubscriptionFuzz, CorruptedBuffersNeverCrashAndAreAllCounted) {
  fuzz(originals(&fixtures::sensor_block), 1, kFuzzRounds);
  fuzz(originals(&fixtures::command_block), 2, kFuzzRounds);
  fuzz(originals(&fixtures::trajectory), 3, kFuzzRounds);
  fuzz(originals(&fixtures::params), 4, kFuzzRounds);
  fuzz(originals(&fixtures::status), 5, kFuzzRounds);
  fuzz(originals(&fixtures::control), 6, kFuzzRounds);
}

// Storage for MAX_VALUES is reserved at construction: blocks of any size, and the corrupt
// ones, are received without allocating.
TEST_F(SubscriptionTest, ReceivingBlocksOfAnySizeAllocatesNothing) {
  std::int64_t last = -1;
  std::size_t ticks = 0;
  Subscription<command_block_t> command(lcm_, "HX_COMMAND", [&](const command_block_t& m, std::int64_t) {
    last = m.seq;
    ticks += m.u_ff_V.size();
  });
  Subscription<sensor_block_t> sensor(lcm_, "HX_SENSOR");
  const auto small = fixtures::encode(fixtures::command_block(9));
  const auto largest = fixtures::encode(fixtures::command_ticks(0, command_block_t::MAX_TICKS, 0));
  const auto sensor_largest = fixtures::encode(fixtures::sensor_ticks(0, sensor_block_t::MAX_TICKS));
  auto bad = small;
  bad.resize(20);
  testing::AllocationCounter counter;
  for (int i = 0; i < 100; ++i) {
    command.receive(largest.data(), largest.size(), 0);
    command.receive(small.data(), small.size(), 0);
    command.receive(bad.data(), bad.size(), 0);
    sensor.receive(sensor_largest.data(), sensor_largest.size(), 0);
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(last, fixtures::command_block(9).seq);
  EXPECT_EQ(ticks, 100u * (static_cast<std::size_t>(command_block_t::MAX_TICKS) + 3u));
  EXPECT_EQ(command.counters().rejected(RejectReason::kDecodeFailed), 100u);
  EXPECT_EQ(sensor.counters().accepted, 100u);
}

// A value count past MAX_VALUES (or beyond the bytes) must not reach decode, which would
// resize every array to it: the wire-layout walk refuses it first.
TEST_F(SubscriptionTest, ACorruptedTickCountIsADecodeFailureAndAllocatesNothing) {
  Subscription<sensor_block_t> sensor(lcm_, "HX_SENSOR");
  const auto good = fixtures::encode(fixtures::sensor_block(3));
  constexpr std::size_t kCountOffset = 8 + 8 + 8 + 8 + 4 + 4 + 1;  // n_values
  ASSERT_EQ(good[kCountOffset + 3], 4u);
  testing::AllocationCounter counter;
  for (const std::uint32_t bad : {0x7fffffffu, 0x10000000u, 3001u, 5u, 0xffffffffu}) {
    std::array<std::uint8_t, 512> bytes{};
    ASSERT_LE(good.size(), bytes.size());
    std::copy(good.begin(), good.end(), bytes.begin());
    for (std::size_t i = 0; i < 4; ++i) bytes[kCountOffset + i] = static_cast<std::uint8_t>(bad >> (24 - 8 * i));
    sensor.receive(bytes.data(), good.size(), 0);
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(sensor.counters().rejected(RejectReason::kDecodeFailed), 5u);
  EXPECT_EQ(sensor.valid_count(), 0u);
}

// Decoding into the reused message: a short block after a long one holds only its own ticks.
TEST_F(SubscriptionTest, AShortBlockAfterALongOneDecodesOnlyItsTicks) {
  Subscription<sensor_block_t> sensor(lcm_, "HX_SENSOR");
  for (std::int64_t k : {9, 0, 9, 1}) {  // 10, 1, 10, 2 ticks
    const auto bytes = fixtures::encode(fixtures::sensor_block(k));
    sensor.receive(bytes.data(), bytes.size(), 0);
    EXPECT_EQ(fixtures::encode(sensor.latest()), bytes) << k;
  }
  EXPECT_EQ(sensor.latest().y_m.size(), 2u);
  EXPECT_EQ(sensor.counters().accepted, 4u);
}

TEST_F(SubscriptionTest, ReceivingTheLargestTrajectoryAllocatesNothingAfterConstruction) {
  Subscription<trajectory_t> traj(lcm_, "HX_TRAJECTORY");
  auto big = fixtures::trajectory(0);
  big.n_points = trajectory_t::MAX_POINTS;
  big.points_t_s.resize(trajectory_t::MAX_POINTS);
  big.points_y_m.assign(trajectory_t::MAX_POINTS, 1e-7);
  for (int i = 0; i < trajectory_t::MAX_POINTS; ++i) big.points_t_s[static_cast<std::size_t>(i)] = 0.01 * i;
  const auto bytes = fixtures::encode(big);
  testing::AllocationCounter counter;
  for (int i = 0; i < 10; ++i) traj.receive(bytes.data(), bytes.size(), 0);
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(traj.counters().accepted, 10u);
}

TEST_F(SubscriptionTest, UnsubscribesWhenDestroyed) {
  int calls = 0;
  {
    Subscription<sensor_block_t> sensor(lcm_, "HX_SENSOR", [&](const sensor_block_t&, std::int64_t) { ++calls; });
  }
  Publisher<sensor_block_t> pub(lcm_, "HX_SENSOR");
  pub.publish(fixtures::sensor_block(0));
  drain();
  EXPECT_EQ(calls, 0);
}

}  // namespace
}  // namespace hystloop
