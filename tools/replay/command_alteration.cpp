#include "command_alteration.hpp"

#include <bit>
#include <stdexcept>
#include <vector>

#include "decode.hpp"
#include "log_reader.hpp"

namespace hystloop::replay {

AlterationResult write_altered_log(const std::filesystem::path& log, const std::filesystem::path& out,
                                   const ChannelNames& channels, const CommandAlteration& alteration) {
  lcm::LogFile writer(out.string(), "w");
  if (!writer.good()) throw std::runtime_error(out.string() + ": cannot open for writing");
  std::optional<AlterationResult> done;
  actuator_command_t msg;
  std::vector<std::uint8_t> buffer;
  std::int64_t commands_seen = 0;
  report::for_each_event({log}, [&](const lcm::LogEvent& event) {
    lcm::LogEvent copy = event;
    const bool is_command = !done && event.channel == channels.command && report::decode_checked(event, msg);
    const bool chosen = is_command && (alteration.nth ? ++commands_seen == *alteration.nth : msg.seq == alteration.seq);
    if (chosen) {
      const double old_u = msg.u_V;
      msg.u_V = alteration.delta_V ? old_u + *alteration.delta_V
                                   : std::bit_cast<double>(std::bit_cast<std::uint64_t>(old_u) ^ 1u);
      buffer.resize(static_cast<std::size_t>(msg.getEncodedSize()));
      msg.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
      copy.data = buffer.data();
      copy.datalen = static_cast<std::int32_t>(buffer.size());
      done = AlterationResult{msg.seq, old_u, msg.u_V};
    }
    if (writer.writeEvent(&copy) != 0) throw std::runtime_error(out.string() + ": write failed");
  });
  if (!done) {
    const std::string which = alteration.nth ? "no command number " + std::to_string(*alteration.nth)
                                             : "no command for tick " + std::to_string(alteration.seq);
    throw std::runtime_error(log.string() + ": " + which + " on " + channels.command);
  }
  return *done;
}

}  // namespace hystloop::replay
