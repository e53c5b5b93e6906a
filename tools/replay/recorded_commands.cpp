#include "recorded_commands.hpp"

#include "decode.hpp"
#include "log_reader.hpp"

namespace hystloop::replay {

CommandLog read_commands(const std::filesystem::path& log, const ChannelNames& channels) {
  CommandLog out;
  actuator_command_t msg;
  report::for_each_event({log}, [&](const lcm::LogEvent& event) {
    if (event.channel != channels.command) return;
    if (!report::decode_checked(event, msg)) return void(++out.undecodable);
    const RecordedCommand c{msg.seq,    msg.sample_seq, msg.u_V,          msg.u_ff_V,
                            msg.u_fb_V, msg.y_ref_m,    msg.params_version, msg.mode};
    if (!out.by_seq.emplace(c.seq, c).second) ++out.duplicates;
  });
  return out;
}

std::set<std::int64_t> read_sample_seqs(const std::filesystem::path& log, const ChannelNames& channels) {
  std::set<std::int64_t> seqs;
  sensor_sample_t msg;
  report::for_each_event({log}, [&](const lcm::LogEvent& event) {
    if (event.channel == channels.sensor && report::decode_checked(event, msg)) seqs.insert(msg.seq);
  });
  return seqs;
}

}  // namespace hystloop::replay
