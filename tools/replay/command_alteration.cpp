#include "command_alteration.hpp"

#include <array>
#include <bit>
#include <set>
#include <span>
#include <stdexcept>
#include <vector>

#include "decode.hpp"
#include "lcm/blocks.hpp"
#include "log_reader.hpp"

namespace hystloop::replay {

AlterationResult write_altered_log(const std::filesystem::path& log, const std::filesystem::path& out,
                                   const ChannelNames& channels, const CommandAlteration& alteration) {
  lcm::LogFile writer(out.string(), "w");
  if (!writer.good()) throw std::runtime_error(out.string() + ": cannot open for writing");
  std::optional<AlterationResult> done;
  command_block_t msg, altered;
  std::vector<std::uint8_t> buffer;
  std::set<std::int64_t> seen;  // ticks commanded so far (for nth)
  const auto changed = [&](double u) {
    return alteration.delta_V ? u + *alteration.delta_V : std::bit_cast<double>(std::bit_cast<std::uint64_t>(u) ^ 1u);
  };
  report::for_each_event({log}, [&](const lcm::LogEvent& event) {
    lcm::LogEvent copy = event;
    if (!done && event.channel == channels.command && report::decode_checked(event, msg)) {
      std::optional<std::int64_t> target;
      for_each_tick(msg, [&](const CommandTick& t) {
        const bool first_time = seen.insert(t.seq).second;
        const bool wanted =
            alteration.nth ? static_cast<std::int64_t>(seen.size()) == *alteration.nth : t.seq == alteration.seq;
        if (!target && first_time && wanted) target = t.seq;
      });
      if (target) {
        // The block rebuilt with every axis it carries; x's command at the target tick altered.
        const std::size_t axes = axes_of(msg);
        begin_block(altered, msg.seq, msg.utime, msg.sample_seq, static_cast<int>(axes));
        for (std::size_t i = 0, n = ticks_of(msg); i < n; ++i) {
          std::array<CommandTick, command_block_t::MAX_AXES> tick{};
          for (std::size_t a = 0; a < axes; ++a) tick[a] = command_tick(msg, i, a);
          if (tick[0].seq == *target) {
            done = AlterationResult{tick[0].seq, tick[0].u_ff_V, changed(tick[0].u_ff_V)};
            tick[0].u_ff_V = done->new_u_ff_V;
          }
          append_tick(altered, std::span<const CommandTick>(tick.data(), axes));
        }
        buffer.resize(static_cast<std::size_t>(altered.getEncodedSize()));
        altered.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
        copy.data = buffer.data();
        copy.datalen = static_cast<std::int32_t>(buffer.size());
      }
    }
    if (writer.writeEvent(&copy) != 0) throw std::runtime_error(out.string() + ": write failed");
  });
  if (!done) {
    const std::string which = alteration.nth ? "no commanded tick number " + std::to_string(*alteration.nth)
                                             : "no command for tick " + std::to_string(alteration.seq);
    throw std::runtime_error(log.string() + ": " + which + " on " + channels.command);
  }
  return *done;
}

}  // namespace hystloop::replay
