#include "replay_inputs.hpp"

#include <set>
#include <stdexcept>

#include <spdlog/fmt/fmt.h>

#include "decode.hpp"
#include "lcm/blocks.hpp"
#include "log_reader.hpp"
#include "recorded_commands.hpp"

namespace hystloop::replay {
namespace {

// start_utime of the compensator's first status and the log's first receive time.
struct LogStart {
  std::optional<std::int64_t> compensator_start_utime;
  std::optional<std::int64_t> first_event_utime;
};

LogStart read_log_start(const std::filesystem::path& log, const ChannelNames& channels, const std::string& process) {
  LogStart s;
  service_status_t status;
  report::for_each_event({log}, [&](const lcm::LogEvent& event) {
    if (!s.first_event_utime) s.first_event_utime = event.timestamp;
    if (s.compensator_start_utime || event.channel != channels.status) return;
    if (report::decode_checked(event, status) && status.process == process)
      s.compensator_start_utime = status.start_utime;
  });
  return s;
}

bool is_other_input(const std::string& channel, const ChannelNames& c) {
  return channel == c.trajectory || channel == c.scan || channel == c.params || channel == c.model ||
         channel == c.control;
}

template <class T>
bool decodes(const lcm::LogEvent& event) {
  T msg;
  return report::decode_checked(event, msg);
}

bool other_input_decodes(const lcm::LogEvent& event, const ChannelNames& c) {
  if (event.channel == c.trajectory) return decodes<trajectory_t>(event);
  if (event.channel == c.scan) return decodes<scan_t>(event);
  if (event.channel == c.params) return decodes<mem_params_t>(event);
  if (event.channel == c.model) return decodes<model_params_t>(event);
  return decodes<control_t>(event);
}

// True if one of `answered` lies in the block's ticks.
bool answers_block(const std::set<std::int64_t>& answered, const sensor_block_t& block) {
  const auto it = answered.lower_bound(block.seq);
  return it != answered.end() && *it <= last_seq(block);
}

}  // namespace

ReplayInputSelection write_replay_inputs(const std::filesystem::path& log, const std::filesystem::path& out,
                                         const ChannelNames& channels, const ReplayInputOptions& options) {
  ReplayInputSelection sel;
  const std::set<std::int64_t> answered = read_commands(log, channels).answered_samples;
  if (answered.empty())
    throw std::runtime_error(log.string() + ": no " + channels.command +
                             " command block answering a sample: nothing to replay against");
  sel.first_answered_sample = *answered.begin();
  const LogStart start = read_log_start(log, channels, options.compensator_process);
  sel.compensator_start_utime = start.compensator_start_utime;
  sel.log_starts_after_compensator = start.compensator_start_utime && start.first_event_utime &&
                                     *start.first_event_utime > *start.compensator_start_utime;

  lcm::LogFile writer(out.string(), "w");
  if (!writer.good()) throw std::runtime_error(out.string() + ": cannot open for writing");
  bool started = false;  // reached the first answered sensor block
  sensor_block_t block;
  report::for_each_event({log}, [&](const lcm::LogEvent& event) {
    if (event.channel == channels.sensor) {
      if (!report::decode_checked(event, block)) return void(++sel.undecodable);
      if (!sel.first_log_sample) sel.first_log_sample = block.seq;
      if (last_seq(block) < *sel.first_answered_sample) return void(++sel.blocks_before_start);
      started = true;
      if (!answers_block(answered, block)) {
        ++sel.blocks_unanswered;
        if (options.only_answered) return void(++sel.blocks_unanswered_dropped);
      }
      ++sel.blocks_written;
      sel.ticks_written += static_cast<std::uint64_t>(block.n_ticks);
    } else if (is_other_input(event.channel, channels)) {
      if (!other_input_decodes(event, channels)) return void(++sel.undecodable);
      const bool running =
          started || (start.compensator_start_utime && event.timestamp >= *start.compensator_start_utime);
      if (!running) return void(++sel.other_inputs_skipped);
      ++sel.other_inputs_written;
    } else {
      return;
    }
    lcm::LogEvent copy = event;  // writeEvent takes a non-const pointer
    if (writer.writeEvent(&copy) != 0) throw std::runtime_error(out.string() + ": write failed");
  });
  return sel;
}

std::string describe(const ReplayInputSelection& s) {
  std::string out = fmt::format("log's first sample: {}; first sample the recorded compensator answered: {}\n",
                                s.first_log_sample.value_or(-1), s.first_answered_sample.value_or(-1));
  if (s.blocks_before_start > 0) {
    out += fmt::format(
        "warm-up: the recorded compensator started after the log did; the replay starts with the block of "
        "sample {} ({} earlier sensor blocks left out)\n",
        s.first_answered_sample.value_or(-1), s.blocks_before_start);
  }
  if (s.log_starts_after_compensator) {
    out +=
        "warning: the log begins after the recorded compensator started: inputs it received before are not in the log, "
        "the replay may diverge\n";
  }
  out += fmt::format(
      "replay inputs: {} sensor blocks ({} ticks), {} trajectory/scan/params/model/control messages ({} logged "
      "before the compensator ran, left out)\n",
      s.blocks_written, s.ticks_written, s.other_inputs_written, s.other_inputs_skipped);
  if (s.blocks_unanswered > 0) {
    out += fmt::format("the recorded compensator did not answer {} sensor blocks after its first ({} left out)\n",
                       s.blocks_unanswered, s.blocks_unanswered_dropped);
  }
  if (s.undecodable > 0) out += fmt::format("{} input events did not decode and were left out\n", s.undecodable);
  return out;
}

}  // namespace hystloop::replay
