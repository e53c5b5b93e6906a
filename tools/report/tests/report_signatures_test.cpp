// A log of a keyed rig read with and without the rig's key: with it, what the rig refused
// (unsigned sensor blocks far ahead, an unsigned parameter set of version 2^31-1) is left out
// and counted; without it, the reader says the log was recorded keyed and not verified.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "auth/message_auth.hpp"
#include "lcm/blocks.hpp"
#include "lcm/channels.hpp"
#include "lcm/rig_auth.hpp"
#include "log_reader.hpp"
#include "log_test_support.hpp"
#include "record/record_auth.hpp"

namespace hystloop::report {
namespace {

namespace fs = std::filesystem;
using test::Event;

constexpr std::int64_t kT0 = 1'700'000'000'000'000;  // [us]

std::shared_ptr<const RigAuth> key(unsigned char seed) {
  auto auth = std::make_shared<RigAuth>();
  for (std::size_t i = 0; i < auth->key.bytes.size(); ++i)
    auth->key.bytes[i] = static_cast<unsigned char>(static_cast<std::size_t>(seed) * 5 + i);
  return auth;
}

// `e` signed as a publisher on the rig signs it at its receive time.
Event signed_event(MessageSigner& signer, Event e) {
  const std::size_t n = e.bytes.size();
  e.bytes.resize(n + kAuthTrailerBytes);
  signer.sign(e.channel, e.bytes.data(), n, e.t, e.bytes.data() + n);
  return e;
}

sensor_block_t sensor_block(std::int64_t seq) {
  sensor_block_t b{};
  begin_block(b, seq, kT0 + seq * 100, 1e-4);
  for (std::int64_t i = 0; i < 10; ++i) append_tick(b, SensorTick{0, seq + i, 1.0, 1.0, 0.0, 1e-7, 1e-7, 0});
  return b;
}

mem_params_t params(std::int32_t version) {
  mem_params_t p{};
  p.utime = kT0;
  p.version = version;
  p.publisher_id = 5;
  p.c1 = 5e-9;
  p.c2 = 1.5e-12;
  p.c3 = 1.1;
  p.valid = 1;
  p.source = "test";
  return p;
}

class ReportSignatures : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("report_signatures_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    MessageSigner bridge(key(1)->key), reident(key(1)->key);
    std::vector<Event> events;
    const std::vector<std::uint8_t> marker = keyed_record_marker(kT0);
    events.push_back({kT0, names_.prefix + std::string(kRecordSuffix), marker});
    for (std::int64_t k = 0; k < 50; ++k) {
      const std::int64_t t = kT0 + 1000 * (k + 1);
      events.push_back(signed_event(bridge, test::event(t, names_.sensor, sensor_block(10 * k))));
      if (k == 20) {
        for (int i = 0; i < 3; ++i)
          events.push_back(test::event(t + 1 + i, names_.sensor, sensor_block(5000 + 10 * k)));
        events.push_back(signed_event(reident, test::event(t + 10, names_.params, params(3))));
        events.push_back(test::event(t + 20, names_.params, params(2147483647)));
      }
    }
    test::write_events(log_, events);
  }
  void TearDown() override { fs::remove_all(dir_); }

  ChannelNames names_{"HX_"};
  fs::path dir_;
  fs::path log_ = fs::temp_directory_path() / ("report_signatures_test_" + std::to_string(::getpid())) / "keyed.lcmlog";
};

TEST_F(ReportSignatures, WithTheKeyWhatTheRigRefusedIsLeftOutAndCounted) {
  const RunData run = read_logs({log_}, names_, 0, key(1));
  EXPECT_TRUE(run.signatures_verified);
  ASSERT_EQ(run.files.size(), 1u);
  EXPECT_TRUE(run.files[0].recorded_keyed);
  EXPECT_EQ(run.files[0].unverified_left_out, 4u);
  EXPECT_EQ(run.samples.size(), 500u);
  EXPECT_EQ(run.samples.back().seq, 499);
  ASSERT_EQ(run.params.size(), 1u);
  EXPECT_EQ(run.params[0].version, 3);
  const std::vector<std::string> warnings = describe_scan_problems(run.files);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("4 message(s) failed signature verification and were left out (HX_PARAMS: 1 "
                             "unsigned; HX_SENSOR: 3 unsigned)"),
            std::string::npos)
      << warnings[0];
  EXPECT_EQ(log_time_zero_utime({log_}, names_.sensor, key(1)), kT0 + 1000 - 900);
}

TEST_F(ReportSignatures, AnotherKeyLeavesEverySignedMessageOut) {
  const RunData run = read_logs({log_}, names_, 0, key(2));
  EXPECT_TRUE(run.samples.empty());
  EXPECT_TRUE(run.params.empty());
  EXPECT_EQ(run.files[0].unverified_left_out, 50u + 3u + 2u);
}

TEST_F(ReportSignatures, WithoutTheKeyAKeyedLogIsReadUnverifiedAndSaysSo) {
  const RunData run = read_logs({log_}, names_, 0, nullptr);
  EXPECT_FALSE(run.signatures_verified);
  EXPECT_EQ(run.files[0].unverified_left_out, 0u);
  EXPECT_EQ(run.params.size(), 2u);
  const std::vector<std::string> warnings = describe_scan_problems(run.files);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("recorded on a keyed rig; signatures not checked"), std::string::npos) << warnings[0];
}

}  // namespace
}  // namespace hystloop::report
