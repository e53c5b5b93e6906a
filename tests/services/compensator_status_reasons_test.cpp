// What hystloop-compensator's HX_STATUS and log say about two quiet failures, driven through its
// handlers over the in-process memq provider:
// - a forged HX_PARAMS set with the re-identifier's own publisher id and version 2^31 - 1 makes
//   every later set of the re-identifier stale: DEGRADED, naming the publisher and both
//   versions, while its sets keep being refused; HEALTHY again once one is accepted;
// - a confirmed jump ahead and a bridge restart are logged from the tick expected to the tick the
//   stream continues from, each with its own ticks.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include "compensator/compensator_service.hpp"
#include "hystloop/service_status_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/connection.hpp"
#include "lcm/status_counters.hpp"
#include "support/text.hpp"

namespace hystloop {
namespace {

constexpr std::int64_t kBaseUtime = 1'700'000'000'123'456;  // the bridge's wall clock at its tick 0 [us]
constexpr double kDt = 1e-4;                                // [s]
constexpr std::int64_t kReident = 0x7e1d'0001;              // the re-identifier's publisher id

CompensatorSettings settings() {
  CompensatorSettings s = load_compensator_settings(
      Config::load_file(std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/compensator.yaml"));
  s.control.horizon_ticks = 300;
  return s;
}

mem_params_t params(std::int32_t version, double c1, std::int64_t publisher = kReident) {
  mem_params_t p{};
  p.version = version;
  p.publisher_id = publisher;
  p.c1 = c1;
  p.c2 = 1.5e-12;
  p.c3 = 1.1;
  p.valid = 1;
  p.source = "reidentifier@rig";
  return p;
}

struct Harness {
  std::unique_ptr<lcm::LCM> lcm = open_lcm("memq://");
  ChannelNames channels{};
  CompensatorService service{settings(), *lcm, channels};
  Subscription<service_status_t> status{*lcm, channels.status};
  sensor_block_t sensor{};

  Harness() { reserve_storage(sensor); }

  // A sensor block of ticks [seq, seq + n), the stage at rest.
  void send(std::int64_t seq, std::int64_t n = 10) {
    begin_block(sensor, seq, kBaseUtime + seq * 100, kDt);
    for (std::int64_t k = seq; k < seq + n; ++k) {
      append_tick(sensor, SensorTick{kBaseUtime + k * 100, k, 0.0, 0.0, 0.0, std::nan(""), 0.0, 0});
    }
    service.on_sensor(sensor, wall_utime());
  }
  void run(std::int64_t from, std::int64_t n) {
    for (std::int64_t k = from; k < from + n; k += 10) send(k);
  }
  const service_status_t& report() {
    service.report(wall_utime(), false);
    while (handle_pending(*lcm, std::chrono::microseconds(0), 100000) > 0) {
    }
    return status.latest();
  }
};

std::int64_t counter(const service_status_t& s, const std::string& name) {
  const std::optional<std::int64_t> value = find_counter(s, name);
  if (!value) ADD_FAILURE() << name << " not reported";
  return value.value_or(-1);
}

using testing::contains;

TEST(CompensatorStatus, APublisherFrozenOutByAForgedVersionIsDegradedAndNamed) {
  Harness h;
  h.run(0, 100);
  h.service.on_params(params(2, 5.0e-9));  // the re-identifier's, accepted
  ASSERT_EQ(h.report().state, service_status_t::HEALTHY) << h.status.latest().detail;

  constexpr std::int32_t kHuge = std::numeric_limits<std::int32_t>::max();
  h.service.on_params(params(kHuge, 4.0e-9));  // forged with its id: accepted, it is "newer"
  h.service.on_params(params(3, 5.5e-9));      // the re-identifier's next: stale now
  h.run(100, 100);
  const service_status_t& one = h.report();
  EXPECT_EQ(one.state, service_status_t::HEALTHY) << "one refusal may be a late datagram: " << one.detail;

  h.service.on_params(params(4, 5.6e-9));
  h.service.on_params(params(4, 5.6e-9));  // its repeat: below v2^31 - 1 as well
  h.run(200, 100);
  const service_status_t& s = h.report();
  EXPECT_EQ(s.state, service_status_t::DEGRADED);
  EXPECT_TRUE(contains(s.detail, "publisher 7e1d0001")) << s.detail;
  EXPECT_TRUE(contains(s.detail, "below v2147483647 accepted from it")) << s.detail;
  EXPECT_TRUE(contains(s.detail, "the last v4")) << s.detail;
  EXPECT_TRUE(contains(s.detail, "3 in a row")) << s.detail;
  EXPECT_EQ(counter(s, "params_stale"), 3);
  EXPECT_EQ(counter(s, "params_stale_below"), 3);
  EXPECT_EQ(counter(s, "params_stale_repeat"), 0);

  // Another publisher is not affected, and does not clear it.
  h.service.on_params(params(1, 5.2e-9, 0x1de));
  h.run(300, 100);
  EXPECT_EQ(h.report().state, service_status_t::DEGRADED);

  // The forged version's own repeat (equal, not below) is harmless.
  h.service.on_params(params(kHuge, 4.0e-9));
  EXPECT_EQ(h.service.counters().params_stale_repeat, 1u);
}

TEST(CompensatorStatus, RepeatsOfTheAcceptedSetAreNotAFreeze) {
  Harness h;
  h.run(0, 100);
  for (int i = 0; i < 10; ++i) h.service.on_params(params(2, 5.0e-9));  // hystloop-ctl params sends each set 3 times
  h.run(100, 100);
  const service_status_t& s = h.report();
  EXPECT_EQ(s.state, service_status_t::HEALTHY) << s.detail;
  EXPECT_EQ(counter(s, "params_stale"), 9);
  EXPECT_EQ(counter(s, "params_stale_repeat"), 9);
  EXPECT_EQ(counter(s, "params_stale_below"), 0);
}

TEST(CompensatorStatus, AJumpAndARestartAreLoggedFromTheTickExpectedToTheTickTheStreamContinuesFrom) {
  auto out = std::make_shared<std::ostringstream>();
  const auto previous = spdlog::default_logger();
  spdlog::set_default_logger(
      std::make_shared<spdlog::logger>("capture", std::make_shared<spdlog::sinks::ostream_sink_mt>(*out)));
  {
    Harness h;
    h.run(0, 1000);
    h.run(5000, 30);  // a jump ahead, confirmed by its third block
    h.run(1000, 30);  // the old numbering again: a restart, also confirmed, in the same period
    h.report();
  }
  spdlog::set_default_logger(previous);
  const std::string log = out->str();
  EXPECT_TRUE(contains(log, "jumped ahead: tick 1000 was expected, the stream continues from tick 5000 ")) << log;
  EXPECT_TRUE(contains(log, "went back: tick 5030 was expected, the stream continues from tick 1000 ")) << log;
}

}  // namespace
}  // namespace hystloop
