// LoggerService in one process over LCM's in-process memq provider: the receive path
// allocates nothing, the log and the summary hold what was sent, a SHUTDOWN stops it.
#include "logger/logger_service.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/process.hpp"
#include "lcm/blocks.hpp"
#include "lcm/connection.hpp"
#include "lcm/message_storage.hpp"
#include "lcm/publisher.hpp"
#include "lcm/rig_auth.hpp"
#include "record/record_auth.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

namespace fs = std::filesystem;

template <class T>
void publish(lcm::LCM& lcm, const std::string& channel, const T& msg) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
}

// A valid block of `n` ticks from `seq` (values do not matter to the logger).
sensor_block_t sensor_block(std::int64_t seq, int n) {
  sensor_block_t b{};
  begin_block(b, seq, 1000 + 100 * seq, 1e-4);
  for (int i = 0; i < n; ++i) append_tick(b, SensorTick{0, seq + i, 1.0, 1.0, 0.0, 1e-6, 1e-6, 4});
  return b;
}

command_block_t command_block(std::int64_t seq, int n, std::int64_t sample_seq) {
  command_block_t b{};
  begin_block(b, seq, 2000 + 100 * seq, sample_seq);
  for (int i = 0; i < n; ++i) append_tick(b, CommandTick{seq + i, 1.0, 1e-6, 1, command_block_t::MODE_MEM});
  return b;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class LoggerServiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    clear_stop_request();
    dir_ = fs::temp_directory_path() / ("logger_service_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    options_.out_dir = dir_;
    options_.queue_mb = 1.0;
    lcm_ = open_lcm("memq://");
  }
  void TearDown() override {
    clear_stop_request();
    fs::remove_all(dir_);
  }
  void dispatch_all() {
    while (handle_pending(*lcm_, std::chrono::microseconds(0)) > 0) {
    }
  }

  fs::path dir_;
  LoggerOptions options_;
  ChannelNames names_{"HX_"};
  std::unique_ptr<lcm::LCM> lcm_;
};

// Blocks of 10 ticks; sensor blocks 150..152 (ticks 1500..1529) are lost; commands run 200
// ticks ahead and, once, a block of 10 command ticks is lost and another one repeated.
TEST_F(LoggerServiceTest, RecordsEverythingCountsTheTickGapsAndReceivesWithoutAllocating) {
  LoggerService service(*lcm_, names_, options_);
  constexpr int kTicks = 10;
  int sent_blocks = 0, sent_commands = 0;
  std::size_t allocations = 0;
  sensor_block_t sensor = sensor_block(0, kTicks);
  command_block_t command = command_block(200, kTicks, 9);
  for (std::int64_t k = 0; k < 400; ++k) {
    const std::int64_t seq = kTicks * k;
    sensor = sensor_block(seq, kTicks);
    if (k < 150 || k >= 153) {
      publish(*lcm_, names_.sensor, sensor);
      ++sent_blocks;
    }
    command = command_block(seq + 200, kTicks, seq + kTicks - 1);
    if (k != 300) {
      publish(*lcm_, names_.command, command);
      ++sent_commands;
    }
    if (k == 301) {
      publish(*lcm_, names_.command, command);  // sent twice
      ++sent_commands;
    }
    if (k % 100 == 0) publish(*lcm_, names_.prefix + "OTHER_THING", command);  // any channel, any type
    const hystloop::testing::AllocationCounter counter;
    dispatch_all();
    allocations += counter.allocations();
  }
  EXPECT_EQ(allocations, 0u);

  const ChannelTable& channels = service.channels();
  ASSERT_EQ(channels.size(), ChannelTable::kRigChannels + 1);  // the rig's channels from the start, + OTHER_THING
  EXPECT_EQ(channels[0].received, static_cast<std::uint64_t>(sent_blocks));
  EXPECT_EQ(channels[0].sequence.ticks(), static_cast<std::uint64_t>(kTicks * sent_blocks));
  EXPECT_EQ(channels[0].sequence.gap_events(), 1u);
  EXPECT_EQ(channels[0].sequence.missing(), 30u);
  EXPECT_EQ(channels[0].sequence.last_seq(), 3999);
  EXPECT_EQ(channels[1].sequence.gap_events(), 1u);  // silence of < 0.1 s: a gap, not a resume
  EXPECT_EQ(channels[1].sequence.missing(), 10u);
  EXPECT_EQ(channels[1].sequence.duplicates(), 1u);
  EXPECT_EQ(channels[1].sequence.resumes(), 0u);
  EXPECT_EQ(channels[0].undecodable + channels[1].undecodable, 0u);
  const std::size_t other = ChannelTable::kRigChannels;  // the first slot after the rig's
  EXPECT_EQ(channels[other].name_view(), "HX_OTHER_THING");
  EXPECT_EQ(channels[other].kind, SequenceKind::kNone);
  EXPECT_FALSE(channels[other].rig);

  request_stop();
  EXPECT_EQ(service.run(), 0);

  std::vector<fs::path> logs, summaries;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    const std::string name = entry.path().filename().string();
    if (name.ends_with(".lcmlog")) logs.push_back(entry.path());
    if (name.ends_with(".summary.json")) summaries.push_back(entry.path());
  }
  ASSERT_EQ(logs.size(), 1u);
  ASSERT_EQ(summaries.size(), 1u);
  lcm::LogFile log(logs[0].string(), "r");
  int sensor_events = 0, command_events = 0, other_events = 0, status_events = 0;
  std::int64_t last_seq = -1;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel == names_.sensor) {
      ASSERT_EQ(sensor.decode(ev->data, 0, ev->datalen), ev->datalen);
      EXPECT_GT(sensor.seq, last_seq);
      last_seq = sensor.seq;
      ++sensor_events;
    }
    if (ev->channel == names_.status) {  // the logger's own first report, recorded too
      service_status_t status;
      ASSERT_EQ(status.decode(ev->data, 0, ev->datalen), ev->datalen);
      EXPECT_EQ(status.process, "logger");
      EXPECT_EQ(status.state, service_status_t::DEGRADED);
      EXPECT_NE(status.detail.find("1 gap(s), 30 ticks missing on HX_SENSOR"), std::string::npos) << status.detail;
      EXPECT_NE(status.detail.find("1 gap(s), 10 ticks missing on HX_COMMAND"), std::string::npos) << status.detail;
      EXPECT_NE(status.detail.find("1 overlapping/duplicate block(s) on HX_COMMAND"), std::string::npos)
          << status.detail;
      std::map<std::string, std::int64_t> counters;
      for (int i = 0; i < status.n_counters; ++i) counters[status.counter_names[i]] = status.counter_values[i];
      EXPECT_EQ(counters["HX_SENSOR.received"], sent_blocks);
      EXPECT_EQ(counters["HX_SENSOR.missing"], 30);
      EXPECT_EQ(counters["HX_SENSOR.gaps"], 1);
      EXPECT_EQ(counters["HX_COMMAND.missing"], 10);
      EXPECT_EQ(counters["HX_COMMAND.duplicates"], 1);
      EXPECT_EQ(counters.count("HX_COMMAND.resumes"), 1u);
      EXPECT_EQ(counters.count("HX_SENSOR.resumes"), 0u);
      EXPECT_EQ(counters["HX_COMMAND.dropped"], 0);
      EXPECT_EQ(counters["files"], 1);
      EXPECT_EQ(counters["other_channels"], 1);
      EXPECT_EQ(counters["other.received"], 4);
      EXPECT_EQ(counters["disk_errors"], 0);
      EXPECT_EQ(counters["dropped"], 0);
      ++status_events;
    }
    command_events += ev->channel == names_.command;
    other_events += ev->channel == "HX_OTHER_THING";
  }
  EXPECT_EQ(sensor_events, sent_blocks);
  EXPECT_EQ(command_events, sent_commands);
  EXPECT_EQ(other_events, 4);
  EXPECT_EQ(status_events, 1);

  const std::string summary = read_text(summaries[0]);
  const auto json = nlohmann::json::parse(summary);
  EXPECT_EQ(json["channels"]["HX_SENSOR"]["sequence"]["gaps"], nlohmann::json::parse("[[1500, 1529]]")) << summary;
  EXPECT_EQ(json["channels"]["HX_COMMAND"]["sequence"]["gaps"], nlohmann::json::parse("[[3200, 3209]]")) << summary;
  EXPECT_EQ(json["totals"]["missing"], 40);
  EXPECT_EQ(json["totals"]["skipped"], 0);
  EXPECT_EQ(json["stop_reason"], "stop request");
  EXPECT_EQ(json["dropped"]["queue_full"], 0);
}

// The compensator stops for longer than logger.command_resume_s, then plans from a later
// tick: a resume with its skipped ticks on HX_STATUS, not a loss; a block that is not a
// command block on HX_COMMAND is recorded and counted as undecodable.
TEST_F(LoggerServiceTest, ACompensatorResumingAfterSilenceIsCountedApart) {
  options_.command_resume_s = 0.02;
  LoggerService service(*lcm_, names_, options_);
  for (std::int64_t k = 0; k < 10; ++k) publish(*lcm_, names_.command, command_block(200 + 10 * k, 10, 10 * k + 9));
  dispatch_all();
  // a duration: the silence itself, which the logger measures between the blocks' receive times;
  // sleep_for waits at least this long however busy the machine (twice command_resume_s).
  std::this_thread::sleep_for(std::chrono::milliseconds(40));
  publish(*lcm_, names_.command, command_block(1000, 10, 800));
  publish(*lcm_, names_.command, sensor_block(0, 3));
  dispatch_all();
  const ChannelSlot& slot = service.channels()[1];
  EXPECT_EQ(slot.name_view(), "HX_COMMAND");
  EXPECT_EQ(slot.sequence.resumes(), 1u);
  EXPECT_EQ(slot.sequence.skipped(), 700u);  // 300..999
  EXPECT_EQ(slot.sequence.missing(), 0u);
  EXPECT_EQ(slot.undecodable, 1u);
  EXPECT_EQ(slot.received, 12u);
  request_stop();
  EXPECT_EQ(service.run(), 0);
  EXPECT_EQ(slot.written.load(), 12u);
}

TEST_F(LoggerServiceTest, AFullQueueDropsAndCountsEveryMessage) {
  options_.queue_mb = 0.02;  // 20000 bytes: ~40 blocks
  options_.flush_interval_s = 1.0;
  LoggerService service(*lcm_, names_, options_);
  // Faster than any disk thread wakes (it dozes 1 ms): most of a burst is refused.
  for (std::int64_t k = 0; k < 2000; ++k) publish(*lcm_, names_.sensor, sensor_block(10 * k, 10));
  dispatch_all();
  const ChannelSlot& slot = service.channels()[0];
  EXPECT_EQ(slot.received, 2000u);
  EXPECT_GT(slot.dropped_queue_full, 0u);
  request_stop();
  EXPECT_EQ(service.run(), 0);
  EXPECT_EQ(slot.written.load() + slot.dropped(), 2000u);
  EXPECT_EQ(slot.sequence.missing(), 0u);  // the network lost nothing: drops are the logger's own
}

// 64+ junk channel names sent before the rig starts filled the table and nothing of
// the rig was recorded. Now the rig's channels are recorded whatever came first, the junk is
// counted (bounded), and its names reach HX_STATUS escaped.
TEST_F(LoggerServiceTest, JunkChannelsSentFirstDoNotBlindTheLogger) {
  LoggerService service(*lcm_, names_, options_);
  const command_block_t junk = command_block(0, 1, 0);
  for (int i = 0; i < 200; ++i) {
    std::string name = names_.prefix + "JUNK";
    name += std::to_string(i);
    if (i == 60) name += "\x1b[2J";  // a terminal escape off the wire
    publish(*lcm_, name, junk);
  }
  dispatch_all();
  for (std::int64_t k = 0; k < 50; ++k) {
    publish(*lcm_, names_.sensor, sensor_block(10 * k, 10));
    publish(*lcm_, names_.command, command_block(10 * k + 200, 10, 10 * k + 9));
  }
  dispatch_all();
  const ChannelTable& channels = service.channels();
  EXPECT_EQ(channels[0].received, 50u);
  EXPECT_EQ(channels[1].received, 50u);
  EXPECT_EQ(channels.unknown().messages(), 200u - (ChannelTable::kMaxChannels - ChannelTable::kRigChannels));
  request_stop();
  EXPECT_EQ(service.run(), 0);
  EXPECT_EQ(channels[0].written.load(), 50u);
  EXPECT_EQ(channels[1].written.load(), 50u);
  std::string summary;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    if (entry.path().string().ends_with(".summary.json")) summary = read_text(entry.path());
  }
  const std::string unknown = std::to_string(200u - (ChannelTable::kMaxChannels - ChannelTable::kRigChannels));
  const auto json = nlohmann::json::parse(summary);
  EXPECT_EQ(json["unknown_channels"]["messages"].dump(), unknown) << summary;
  EXPECT_EQ(json["unknown_channels"]["distinct"].dump(), unknown);
  // A name with a control character is kept, escaped for the JSON (and for a terminal that cats it).
  EXPECT_NE(summary.find("\"HX_JUNK60\\u001b[2J\""), std::string::npos) << summary;
  EXPECT_EQ(json["disk"]["ok"], true);
}

std::shared_ptr<const RigAuth> rig_key(unsigned char seed) {
  auto auth = std::make_shared<RigAuth>();
  for (std::size_t i = 0; i < auth->key.bytes.size(); ++i)
    auth->key.bytes[i] = static_cast<unsigned char>(static_cast<std::size_t>(seed) * 3 + i);
  return auth;
}

// The process's rig key for one test (a service's main sets it).
struct ProcessAuth {
  explicit ProcessAuth(std::shared_ptr<const RigAuth> a) { set_process_rig_auth(std::move(a)); }
  ~ProcessAuth() { set_process_rig_auth(nullptr); }
};

// On a keyed rig the record holds what the rig would take: unsigned blocks far ahead, command
// blocks signed with another key and a replayed block are not recorded, not counted as gaps or
// out-of-order blocks, and are counted by channel and reason on HX_STATUS and in the summary;
// the log starts with the keyed marker.
TEST_F(LoggerServiceTest, OnAKeyedRigWhatFailsItsSignatureIsCountedNotRecorded) {
  const ProcessAuth keyed(rig_key(1));
  LoggerService service(*lcm_, names_, options_);
  Publisher<sensor_block_t> sensor(*lcm_, names_.sensor);
  Publisher<command_block_t> command(*lcm_, names_.command);
  Publisher<sensor_block_t> unsigned_sensor(*lcm_, names_.sensor, default_message_check<sensor_block_t>(), nullptr);
  Publisher<command_block_t> foreign_command(*lcm_, names_.command, default_message_check<command_block_t>(),
                                             rig_key(2));
  std::vector<std::uint8_t> last_signed;
  lcm_subscription_t* keep = lcm_subscribe(
      lcm_->getUnderlyingLCM(), names_.sensor.c_str(),
      [](const lcm_recv_buf_t* rbuf, const char*, void* out) {
        const auto* b = static_cast<const std::uint8_t*>(rbuf->data);
        static_cast<std::vector<std::uint8_t>*>(out)->assign(b, b + rbuf->data_size);
      },
      &last_signed);
  constexpr int kTicks = 10, kBlocks = 100;
  for (std::int64_t k = 0; k < kBlocks; ++k) {
    ASSERT_TRUE(sensor.publish(sensor_block(kTicks * k, kTicks)));
    ASSERT_TRUE(command.publish(command_block(kTicks * k + 200, kTicks, kTicks * k + kTicks - 1)));
    if (k == 50) {
      dispatch_all();
      const std::vector<std::uint8_t>& replay = last_signed;
      for (int i = 0; i < 3; ++i) ASSERT_TRUE(unsigned_sensor.publish(sensor_block(kTicks * k + 5000, kTicks)));
      for (int i = 0; i < 7; ++i) ASSERT_TRUE(foreign_command.publish(command_block(kTicks * k + 9000, kTicks, 0)));
      lcm_->publish(names_.sensor, replay.data(), static_cast<unsigned>(replay.size()));
    }
    dispatch_all();
  }
  lcm_unsubscribe(lcm_->getUnderlyingLCM(), keep);

  const ChannelTable& channels = service.channels();
  EXPECT_EQ(channels[0].received, static_cast<std::uint64_t>(kBlocks + 4));
  EXPECT_EQ(channels[0].sequence.gap_events(), 0u);
  EXPECT_EQ(channels[0].sequence.missing(), 0u);
  EXPECT_EQ(channels[0].sequence.out_of_order(), 0u);
  EXPECT_EQ(channels[0].sequence.duplicates(), 0u);
  EXPECT_EQ(channels[1].sequence.gap_events(), 0u);
  EXPECT_EQ(channels[1].sequence.out_of_order(), 0u);
  EXPECT_EQ(channels[0].refused[static_cast<std::size_t>(AuthResult::kUnsigned)], 3u);
  EXPECT_EQ(channels[0].refused[static_cast<std::size_t>(AuthResult::kReplayed)], 1u);
  EXPECT_EQ(channels[1].refused[static_cast<std::size_t>(AuthResult::kBadMac)], 7u);

  request_stop();
  EXPECT_EQ(service.run(), 0);

  std::vector<fs::path> logs, summaries;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    const std::string name = entry.path().filename().string();
    if (name.ends_with(".lcmlog")) logs.push_back(entry.path());
    if (name.ends_with(".summary.json")) summaries.push_back(entry.path());
  }
  ASSERT_EQ(logs.size(), 1u);
  lcm::LogFile log(logs[0].string(), "r");
  int sensor_events = 0, command_events = 0, events = 0, status_events = 0;
  bool marker_first = false;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (events++ == 0) marker_first = is_keyed_record_marker(ev->channel, ev->data, ev->datalen);
    sensor_events += ev->channel == names_.sensor;
    command_events += ev->channel == names_.command;
    if (ev->channel == names_.status) {
      service_status_t status;
      ASSERT_GT(status.decode(ev->data, 0, ev->datalen), 0);
      if (status.process != "logger") continue;
      std::map<std::string, std::int64_t> counters;
      for (int i = 0; i < status.n_counters; ++i) counters[status.counter_names[i]] = status.counter_values[i];
      EXPECT_EQ(counters["keyed"], 1);
      EXPECT_EQ(counters["HX_SENSOR.rejected_unsigned"], 3);
      EXPECT_EQ(counters["HX_SENSOR.rejected_replayed"], 1);
      EXPECT_EQ(counters["HX_COMMAND.rejected_bad_mac"], 7);
      EXPECT_EQ(counters["rejected_auth"], 11);
      EXPECT_NE(status.detail.find("refused 7 message(s) whose signature failed (7 bad_mac; not recorded) on "
                                   "HX_COMMAND"),
                std::string::npos)
          << status.detail;
      ++status_events;
    }
  }
  EXPECT_TRUE(marker_first);
  EXPECT_EQ(sensor_events, kBlocks);
  EXPECT_EQ(command_events, kBlocks);
  EXPECT_EQ(status_events, 1);
  ASSERT_EQ(summaries.size(), 1u);
  const auto json = nlohmann::json::parse(read_text(summaries[0]));
  EXPECT_EQ(json["keyed"], true);
  EXPECT_EQ(json["channels"]["HX_SENSOR"]["refused"]["unsigned"], 3);
  EXPECT_EQ(json["channels"]["HX_COMMAND"]["refused"]["bad_mac"], 7);
  EXPECT_EQ(json["totals"]["gap_events"], 0);
}

TEST_F(LoggerServiceTest, ShutdownForTheLoggerStopsIt) {
  LoggerService service(*lcm_, names_, options_);
  control_t msg{};
  msg.request_id = 7;
  msg.command = control_t::SHUTDOWN;
  msg.target = "compensator";
  publish(*lcm_, names_.control, msg);
  dispatch_all();
  EXPECT_FALSE(stop_requested());
  msg.request_id = 8;
  msg.target = "logger";
  publish(*lcm_, names_.control, msg);
  dispatch_all();
  EXPECT_TRUE(stop_requested());
  EXPECT_EQ(service.run(), 0);
}

}  // namespace
}  // namespace hystloop
