#include "recorded_commands.hpp"

#include <algorithm>

#include "decode.hpp"
#include "lcm/blocks.hpp"
#include "log_reader.hpp"

namespace hystloop::replay {

CommandLog read_commands(const std::filesystem::path& log, const ChannelNames& channels, int axis) {
  CommandLog out;
  command_block_t block;
  report::for_each_event({log}, [&](const lcm::LogEvent& event) {
    if (event.channel != channels.command) return;
    if (!report::decode_checked(event, block)) return void(++out.undecodable);
    ++out.blocks;
    if (block.sample_seq >= 0) out.answered_samples.insert(block.sample_seq);
    const auto axes = static_cast<int>(axes_of(block));
    out.axes = std::max(out.axes, axes);
    if (axis >= axes) return;
    for_each_tick(
        block,
        [&](const CommandTick& t) {
          const RecordedCommand c{t.seq, block.sample_seq, t.u_ff_V, t.y_ref_m, t.params_version, t.mode};
          if (!out.by_seq.emplace(c.seq, c).second) ++out.duplicates;
        },
        static_cast<std::size_t>(axis));
  });
  return out;
}

std::set<std::int64_t> read_sample_seqs(const std::filesystem::path& log, const ChannelNames& channels) {
  std::set<std::int64_t> seqs;
  sensor_block_t block;
  report::for_each_event({log}, [&](const lcm::LogEvent& event) {
    if (event.channel != channels.sensor || !report::decode_checked(event, block)) return;
    for_each_tick(block, [&](const SensorTick& t) { seqs.insert(t.seq); });
  });
  return seqs;
}

}  // namespace hystloop::replay
