// hystloop-compensator on a keyed rig (README "Authenticated rig"), over memq: trajectories,
// parameter sets and control requests from a publisher without the key, with another key, or
// replayed are refused and counted by reason on HX_STATUS; signed ones act; the compensator's
// own command blocks are signed.
#include <gtest/gtest.h>

#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "compensator/compensator_service.hpp"
#include "compensator/compensator_settings.hpp"
#include "core/clock.hpp"
#include "lcm/blocks.hpp"
#include "lcm/connection.hpp"
#include "lcm/rig_auth.hpp"

namespace hystloop {
namespace {

std::shared_ptr<const RigAuth> rig(unsigned char seed) {
  auto auth = std::make_shared<RigAuth>();
  for (std::size_t i = 0; i < auth->key.bytes.size(); ++i)
    auth->key.bytes[i] = static_cast<unsigned char>(static_cast<std::size_t>(seed) * 3 + i);
  return auth;
}

// The process's rig auth for one test (main sets it in a service).
struct ProcessAuth {
  explicit ProcessAuth(std::shared_ptr<const RigAuth> a) { set_process_rig_auth(std::move(a)); }
  ~ProcessAuth() { set_process_rig_auth(nullptr); }
};

control_t set_mode(std::int64_t id, std::int8_t mode) {
  control_t c{};
  c.utime = wall_utime();
  c.request_id = id;
  c.command = control_t::SET_MODE;
  c.mode = mode;
  return c;
}

mem_params_t params(std::int32_t version) {
  mem_params_t p{};
  p.utime = wall_utime();
  p.version = version;
  p.publisher_id = 77;
  p.c1 = 5e-9;
  p.c2 = 1.5e-12;
  p.c3 = 1.1;
  p.valid = true;
  p.source = "test";
  return p;
}

trajectory_t hold(std::int64_t version) {
  trajectory_t t{};
  t.utime = wall_utime();
  t.version = version;
  t.shape = trajectory_t::HOLD;
  t.offset_m = 1e-7;
  return t;
}

struct KeyedRig {
  std::shared_ptr<const RigAuth> key = rig(1);
  ProcessAuth installed{key};
  std::unique_ptr<lcm::LCM> lcm = open_lcm("memq://");
  ChannelNames channels{};
  CompensatorService service{load_compensator_settings(Config::load_file(std::string(HYSTLOOP_SOURCE_DIR) +
                                                                         "/deploy/config/compensator.yaml")),
                             *lcm, channels};
  std::vector<std::vector<std::uint8_t>> command_bytes;
  std::vector<std::vector<std::uint8_t>> control_bytes;

  KeyedRig() {
    lcm_subscribe(lcm->getUnderlyingLCM(), channels.command.c_str(), &KeyedRig::keep, &command_bytes);
    lcm_subscribe(lcm->getUnderlyingLCM(), channels.control.c_str(), &KeyedRig::keep, &control_bytes);
  }
  static void keep(const lcm_recv_buf_t* rbuf, const char*, void* into) {
    const auto* b = static_cast<const std::uint8_t*>(rbuf->data);
    static_cast<std::vector<std::vector<std::uint8_t>>*>(into)->emplace_back(b, b + rbuf->data_size);
  }
  void drain() {
    while (handle_pending(*lcm, std::chrono::microseconds(0), 100000) > 0) {
    }
  }
  std::map<std::string, std::int64_t> status() {
    Subscription<service_status_t> sub(*lcm, channels.status);
    service.report(wall_utime(), false);
    drain();
    std::map<std::string, std::int64_t> out;
    for (std::size_t i = 0; i < sub.latest().counter_names.size(); ++i) {
      out[sub.latest().counter_names[i]] = sub.latest().counter_values[i];
    }
    return out;
  }
};

TEST(CompensatorAuth, MessagesWithoutTheKeyAreRefusedAndCountedByReason) {
  KeyedRig r;
  Publisher<control_t> foreign_control(*r.lcm, r.channels.control, default_message_check<control_t>(), nullptr);
  Publisher<mem_params_t> foreign_params(*r.lcm, r.channels.params, default_message_check<mem_params_t>(), nullptr);
  Publisher<trajectory_t> foreign_traj(*r.lcm, r.channels.trajectory, default_message_check<trajectory_t>(), nullptr);
  Publisher<control_t> other_key(*r.lcm, r.channels.control, default_message_check<control_t>(), rig(2));
  ASSERT_TRUE(foreign_control.publish(set_mode(1, command_block_t::MODE_OFF)));
  ASSERT_TRUE(foreign_params.publish(params(5)));
  ASSERT_TRUE(foreign_traj.publish(hold(3)));
  ASSERT_TRUE(other_key.publish(set_mode(2, command_block_t::MODE_OFF)));
  r.drain();
  EXPECT_EQ(r.service.counters().control_acted, 0u);
  EXPECT_EQ(r.service.counters().trajectories, 0u);
  std::map<std::string, std::int64_t> s = r.status();
  EXPECT_EQ(s["control.rejected_unsigned"], 1);
  EXPECT_EQ(s["control.rejected_bad_mac"], 1);
  EXPECT_EQ(s["params.rejected_unsigned"], 1);
  EXPECT_EQ(s["trajectory.rejected_unsigned"], 1);
  EXPECT_EQ(s["control.accepted"], 0);
  EXPECT_EQ(s["params_accepted"], 0);
}

TEST(CompensatorAuth, SignedMessagesActOnceAndAReplayIsRefused) {
  KeyedRig r;
  Publisher<control_t> ctl(*r.lcm, r.channels.control);  // the process's key
  ASSERT_TRUE(ctl.signs());
  ASSERT_TRUE(ctl.publish(set_mode(1, command_block_t::MODE_OFF)));
  r.drain();
  EXPECT_EQ(r.service.counters().control_acted, 1u);
  ASSERT_EQ(r.control_bytes.size(), 1u);
  const std::vector<std::uint8_t> captured = r.control_bytes[0];
  ASSERT_EQ(r.lcm->publish(r.channels.control, captured.data(), static_cast<unsigned>(captured.size())), 0);
  r.drain();
  std::map<std::string, std::int64_t> s = r.status();
  EXPECT_EQ(s["control.accepted"], 1);
  EXPECT_EQ(s["control.rejected_replayed"], 1);
}

TEST(CompensatorAuth, CommandBlocksAreSigned) {
  KeyedRig r;
  // Made before the blocks are signed (a receiver refuses what was signed before it started);
  // drain() hands it what the service published.
  Subscription<command_block_t>::Options keyed;
  keyed.auth = r.key;
  Subscription<command_block_t> check(*r.lcm, r.channels.command, {}, keyed);
  sensor_block_t block{};
  reserve_storage(block);
  begin_block(block, 0, wall_utime(), 1e-4);
  for (std::int64_t k = 0; k < 20; ++k) append_tick(block, SensorTick{wall_utime(), k, 0.0, 0.0, 0.0, 0.0, 0.0, 0});
  r.service.on_sensor(block, wall_utime());
  r.drain();
  ASSERT_FALSE(r.command_bytes.empty());
  EXPECT_EQ(check.counters().accepted, r.command_bytes.size());
  EXPECT_EQ(check.counters().rejected_total(), 0u);
}

}  // namespace
}  // namespace hystloop
