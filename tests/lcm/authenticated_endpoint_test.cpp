// Publisher and Subscription on a keyed rig (lcm/rig_auth.hpp), over memq://: the
// authenticated channels carry a trailer that a keyed receiver checks and a keyless one
// ignores; unsigned, wrongly signed, replayed, moved and stale messages are refused and
// counted by reason; the other channels are untouched.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <memory>
#include <vector>

#include "core/clock.hpp"
#include "lcm/connection.hpp"
#include "lcm/message_fixtures.hpp"
#include "lcm/publisher.hpp"
#include "lcm/rig_auth.hpp"
#include "lcm/subscription.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using namespace std::chrono_literals;

std::shared_ptr<const RigAuth> rig(unsigned char seed) {
  auto auth = std::make_shared<RigAuth>();
  for (std::size_t i = 0; i < auth->key.bytes.size(); ++i) auth->key.bytes[i] = static_cast<unsigned char>(seed + i);
  return auth;
}

template <class T>
typename Subscription<T>::Options keyed(const std::shared_ptr<const RigAuth>& auth) {
  typename Subscription<T>::Options o;
  o.auth = auth;
  return o;
}

class AuthenticatedEndpointTest : public ::testing::Test {
 protected:
  void SetUp() override {
    lcm_ = std::make_unique<lcm::LCM>("memq://");
    // Every message published on the rig, as sent (a recording).
    lcm_subscribe(lcm_->getUnderlyingLCM(), "HX_.*", &AuthenticatedEndpointTest::record, this);
  }
  static void record(const lcm_recv_buf_t* rbuf, const char* channel, void* self) {
    auto* t = static_cast<AuthenticatedEndpointTest*>(self);
    const auto* b = static_cast<const std::uint8_t*>(rbuf->data);
    t->recorded_.push_back({channel, std::vector<std::uint8_t>(b, b + rbuf->data_size)});
  }
  int drain() { return handle_pending(*lcm_, 0us); }
  void replay(const std::string& channel, const std::vector<std::uint8_t>& bytes) {
    ASSERT_EQ(lcm_->publish(channel, bytes.data(), static_cast<unsigned>(bytes.size())), 0);
  }

  struct Recorded {
    std::string channel;
    std::vector<std::uint8_t> bytes;
  };
  std::unique_ptr<lcm::LCM> lcm_;
  std::vector<Recorded> recorded_;
  const std::shared_ptr<const RigAuth> key_ = rig(1);
};

TEST(RigAuth, AuthenticatedChannelsAreTheOnesThatCanMoveTheStage) {
  for (const char* c :
       {"HX_COMMAND", "HX_CONTROL", "HX_TRAJECTORY", "HX_PARAMS", "HX_MODEL", "HX_SENSOR", "RIG2_PARAMS"}) {
    EXPECT_TRUE(is_authenticated_channel(c)) << c;
  }
  for (const char* c : {"HX_STATUS", "COMMAND", "HX_COMMANDS", "HXCOMMAND", "HX_SENSORS", ""}) {
    EXPECT_FALSE(is_authenticated_channel(c)) << c;
  }
}

TEST_F(AuthenticatedEndpointTest, SignedMessagesArriveIntactAtKeyedAndKeylessReceivers) {
  Subscription<command_block_t> keyed_sub(*lcm_, "HX_COMMAND", {}, keyed<command_block_t>(key_));
  Subscription<command_block_t> keyless_sub(*lcm_, "HX_COMMAND", {}, keyed<command_block_t>(nullptr));
  Publisher<command_block_t> pub(*lcm_, "HX_COMMAND", default_message_check<command_block_t>(), key_);
  ASSERT_TRUE(keyed_sub.authenticated());
  ASSERT_TRUE(pub.signs());
  for (int k = 0; k < 3; ++k) ASSERT_TRUE(pub.publish(fixtures::command_block(k)));
  drain();
  ASSERT_EQ(recorded_.size(), 3u);
  EXPECT_EQ(recorded_[2].bytes.size(), fixtures::encode(fixtures::command_block(2)).size() + kAuthTrailerBytes);
  for (const auto* sub : {&keyed_sub, &keyless_sub}) {
    EXPECT_EQ(sub->counters().accepted, 3u);
    EXPECT_EQ(sub->counters().rejected_total(), 0u);
    EXPECT_EQ(fixtures::encode(sub->latest()), fixtures::encode(fixtures::command_block(2)));
  }
}

TEST_F(AuthenticatedEndpointTest, KeyedReceiverRefusesUnsignedAndWrongKeyAndCountsThem) {
  Subscription<control_t> control(*lcm_, "HX_CONTROL", {}, keyed<control_t>(key_));
  Publisher<control_t> foreign(*lcm_, "HX_CONTROL", default_message_check<control_t>(), nullptr);
  Publisher<control_t> wrong_key(*lcm_, "HX_CONTROL", default_message_check<control_t>(), rig(2));
  ASSERT_FALSE(foreign.signs());
  ASSERT_TRUE(foreign.publish(fixtures::control(1)));
  ASSERT_TRUE(foreign.publish(fixtures::control(2)));
  ASSERT_TRUE(wrong_key.publish(fixtures::control(3)));
  drain();
  EXPECT_EQ(control.counters().accepted, 0u);
  EXPECT_EQ(control.counters().rejected(RejectReason::kUnsigned), 2u);
  EXPECT_EQ(control.counters().rejected(RejectReason::kBadMac), 1u);
  EXPECT_EQ(control.valid_count(), 0u);
}

TEST_F(AuthenticatedEndpointTest, ReplayedMovedAndStaleSignedMessagesAreRefused) {
  Subscription<mem_params_t> params(*lcm_, "HX_PARAMS", {}, keyed<mem_params_t>(key_));
  Subscription<trajectory_t> trajectory(*lcm_, "HX_TRAJECTORY", {}, keyed<trajectory_t>(key_));
  Publisher<mem_params_t> pub(*lcm_, "HX_PARAMS", default_message_check<mem_params_t>(), key_);
  ASSERT_TRUE(pub.publish(fixtures::params(1)));
  drain();
  ASSERT_EQ(params.counters().accepted, 1u);
  ASSERT_EQ(recorded_.size(), 1u);
  const std::vector<std::uint8_t> captured = recorded_[0].bytes;

  replay("HX_PARAMS", captured);  // the same message again
  drain();
  EXPECT_EQ(params.counters().rejected(RejectReason::kReplayed), 1u);

  // Replayed later, after the sender is gone or the receiver restarted: too old.
  Subscription<mem_params_t> restarted(*lcm_, "HX_PARAMS", {}, keyed<mem_params_t>(key_));
  restarted.receive(captured.data(), captured.size(), wall_utime() + key_->max_skew_us + 1'000'000);
  EXPECT_EQ(restarted.counters().rejected(RejectReason::kSkewed), 1u);
  EXPECT_EQ(restarted.counters().accepted, 0u);

  // Another channel's bytes are not this channel's (trailer of the wrong fingerprint aside).
  std::vector<std::uint8_t> traj = fixtures::encode(fixtures::trajectory(1));
  traj.insert(traj.end(), captured.end() - kAuthTrailerBytes, captured.end());
  trajectory.receive(traj.data(), traj.size(), wall_utime());
  EXPECT_EQ(trajectory.counters().rejected(RejectReason::kBadMac), 1u);
}

TEST_F(AuthenticatedEndpointTest, AMessageMovedToAnotherAuthenticatedChannelIsRefused) {
  Subscription<command_block_t> on_a(*lcm_, "HX_COMMAND", {}, keyed<command_block_t>(key_));
  Subscription<command_block_t> on_b(*lcm_, "RIG2_COMMAND", {}, keyed<command_block_t>(key_));
  Publisher<command_block_t> pub(*lcm_, "HX_COMMAND", default_message_check<command_block_t>(), key_);
  ASSERT_TRUE(pub.publish(fixtures::command_block(1)));
  drain();
  replay("RIG2_COMMAND", recorded_.at(0).bytes);
  drain();
  EXPECT_EQ(on_a.counters().accepted, 1u);
  EXPECT_EQ(on_b.counters().rejected(RejectReason::kBadMac), 1u);
}

TEST_F(AuthenticatedEndpointTest, UnauthenticatedChannelsAreNeitherSignedNorChecked) {
  Subscription<service_status_t> status(*lcm_, "HX_STATUS", {}, keyed<service_status_t>(key_));
  Publisher<service_status_t> keyed_pub(*lcm_, "HX_STATUS", default_message_check<service_status_t>(), key_);
  Publisher<service_status_t> keyless_pub(*lcm_, "HX_STATUS", default_message_check<service_status_t>(), nullptr);
  EXPECT_FALSE(status.authenticated());
  EXPECT_FALSE(keyed_pub.signs());
  ASSERT_TRUE(keyed_pub.publish(fixtures::status(1)));
  ASSERT_TRUE(keyless_pub.publish(fixtures::status(2)));
  drain();
  EXPECT_EQ(status.counters().accepted, 2u);
  EXPECT_EQ(recorded_.at(0).bytes, fixtures::encode(fixtures::status(1)));  // today's bytes
}

// The compensator plans from the sensor blocks' tick numbers: on a keyed rig a forged or
// replayed block is refused before its numbers reach the sequence guard.
TEST_F(AuthenticatedEndpointTest, SensorBlocksAreSignedAndAForgedOrReplayedOneIsRefused) {
  Subscription<sensor_block_t> sensor(*lcm_, "HX_SENSOR", {}, keyed<sensor_block_t>(key_));
  Publisher<sensor_block_t> bridge(*lcm_, "HX_SENSOR", default_message_check<sensor_block_t>(), key_);
  Publisher<sensor_block_t> forger(*lcm_, "HX_SENSOR", default_message_check<sensor_block_t>(), nullptr);
  ASSERT_TRUE(sensor.authenticated());
  ASSERT_TRUE(bridge.signs());
  ASSERT_TRUE(bridge.publish(fixtures::sensor_block(1)));
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(forger.publish(fixtures::sensor_block(5000 + i)));  // 3 blocks ahead
  drain();
  replay("HX_SENSOR", recorded_.at(0).bytes);
  drain();
  EXPECT_EQ(sensor.counters().accepted, 1u);
  EXPECT_EQ(sensor.counters().rejected(RejectReason::kUnsigned), 3u);
  EXPECT_EQ(sensor.counters().rejected(RejectReason::kReplayed), 1u);
}

// A receiver made after a message was signed refuses it, though it never saw the sender and the
// message is well within the skew: a captured ARM cannot re-arm a restarted bridge.
TEST_F(AuthenticatedEndpointTest, ARestartedReceiverRefusesWhatWasSignedBeforeItStarted) {
  Publisher<control_t> ctl(*lcm_, "HX_CONTROL", default_message_check<control_t>(), key_);
  ASSERT_TRUE(ctl.publish(fixtures::control(1)));
  drain();
  ASSERT_EQ(recorded_.size(), 1u);
  const std::vector<std::uint8_t> captured = recorded_[0].bytes;
  // The verifier's bound is its construction's wall clock [us]: let it pass the counter (the
  // signing time, at most `now` here).
  const std::int64_t signed_by = wall_utime();
  while (wall_utime() <= signed_by + 1) {
  }
  Subscription<control_t> restarted(*lcm_, "HX_CONTROL", {}, keyed<control_t>(key_));
  restarted.receive(captured.data(), captured.size(), wall_utime());
  EXPECT_EQ(restarted.counters().rejected(RejectReason::kReplayed), 1u);
  EXPECT_EQ(restarted.counters().accepted, 0u);
  ASSERT_TRUE(ctl.publish(fixtures::control(2)));  // the live sender goes on being heard
  drain();
  EXPECT_EQ(restarted.counters().accepted, 1u);
}

TEST_F(AuthenticatedEndpointTest, TrailingBytesThatAreNotATrailerAreSizeMismatch) {
  Subscription<command_block_t> keyed_sub(*lcm_, "HX_COMMAND", {}, keyed<command_block_t>(key_));
  Subscription<command_block_t> keyless_sub(*lcm_, "HX_COMMAND", {}, keyed<command_block_t>(nullptr));
  std::vector<std::uint8_t> bytes = fixtures::encode(fixtures::command_block(1));
  bytes.resize(bytes.size() + kAuthTrailerBytes, 0);  // trailer-sized, no magic
  replay("HX_COMMAND", bytes);
  bytes.resize(bytes.size() - 1);
  std::memcpy(bytes.data() + bytes.size() - kAuthTrailerBytes + 1, "HXA1", 4);
  replay("HX_COMMAND", bytes);  // one short
  drain();
  for (const auto* sub : {&keyed_sub, &keyless_sub}) {
    EXPECT_EQ(sub->counters().rejected(RejectReason::kSizeMismatch), 2u);
    EXPECT_EQ(sub->counters().accepted, 0u);
  }
}

TEST_F(AuthenticatedEndpointTest, SigningAndCheckingAllocateNothing) {
  Subscription<command_block_t> sub(*lcm_, "HX_COMMAND", {}, keyed<command_block_t>(key_));
  Publisher<command_block_t> pub(*lcm_, "HX_COMMAND", default_message_check<command_block_t>(), key_);
  const command_block_t block = fixtures::command_ticks(0, 20, 0);
  ASSERT_TRUE(pub.publish(block));
  std::vector<std::uint8_t> signed_bytes(fixtures::encode(block).size() + kAuthTrailerBytes);
  MessageSigner signer(key_->key);
  const std::vector<std::uint8_t> body = fixtures::encode(block);
  std::memcpy(signed_bytes.data(), body.data(), body.size());
  testing::AllocationCounter counter;
  for (int i = 0; i < 50; ++i) {
    ASSERT_TRUE(pub.publish(block));
    signer.sign("HX_COMMAND", signed_bytes.data(), body.size(), wall_utime(), signed_bytes.data() + body.size());
    sub.receive(signed_bytes.data(), signed_bytes.size(), wall_utime());
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(sub.counters().accepted, 50u);
}

TEST(LcmBodySize, PlainOrTrailerFollowedEncodingsOnly) {
  const std::vector<std::uint8_t> plain = fixtures::encode(fixtures::params(1));
  const auto layout = wire_layout_of<mem_params_t>();
  EXPECT_EQ(lcm_body_size(layout, plain.data(), plain.size()), static_cast<std::int64_t>(plain.size()));
  std::vector<std::uint8_t> with = plain;
  with.resize(plain.size() + kAuthTrailerBytes);
  std::memcpy(with.data() + plain.size(), "HXA1", 4);
  EXPECT_EQ(lcm_body_size(layout, with.data(), with.size()), static_cast<std::int64_t>(plain.size()));
  with[plain.size()] = 'X';
  EXPECT_EQ(lcm_body_size(layout, with.data(), with.size()), -1);
  EXPECT_EQ(lcm_body_size(layout, plain.data(), plain.size() - 1), -1);
}

}  // namespace
}  // namespace hystloop
