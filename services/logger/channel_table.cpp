#include "logger/channel_table.hpp"

#include <cstring>
#include <string>

#include "core/errors.hpp"

namespace hystloop {

namespace {
void copy_name(std::array<char, ChannelSlot::kMaxName + 1>& to, std::string_view name, const char* field) {
  if (name.size() > ChannelSlot::kMaxName) {
    throw ParameterError(field, "longer than " + std::to_string(ChannelSlot::kMaxName) + " characters");
  }
  std::memcpy(to.data(), name.data(), name.size());
  to[name.size()] = '\0';
}
}  // namespace

ChannelTable::ChannelTable(std::string_view sensor_channel, std::string_view command_channel,
                           std::int64_t restart_threshold, std::int64_t command_resume_us)
    : slots_(), command_detector_(restart_threshold, command_resume_us) {  // validates both
  copy_name(sensor_, sensor_channel, "sensor_channel");
  copy_name(command_, command_channel, "command_channel");
  const SequenceGapDetector detector(restart_threshold);
  for (auto& slot : slots_) slot.sequence = detector;
}

std::optional<std::uint32_t> ChannelTable::find_or_add(const char* name) noexcept {
  const std::size_t n = size_.load(std::memory_order_relaxed);
  // Messages mostly alternate between two or three channels: try the last hit first.
  if (last_hit_ < n && std::strcmp(slots_[last_hit_].name.data(), name) == 0) return last_hit_;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (std::strcmp(slots_[i].name.data(), name) == 0) return last_hit_ = i;
  }
  const std::size_t length = std::strlen(name);
  if (n == kMaxChannels || length > ChannelSlot::kMaxName) {
    ++unrecorded_;
    return std::nullopt;
  }
  ChannelSlot& slot = slots_[n];
  std::memcpy(slot.name.data(), name, length + 1);
  slot.name_length = length;
  slot.kind = std::strcmp(name, sensor_.data()) == 0    ? SequenceKind::kSensor
              : std::strcmp(name, command_.data()) == 0 ? SequenceKind::kCommand
                                                        : SequenceKind::kNone;
  if (slot.kind == SequenceKind::kCommand) slot.sequence = command_detector_;
  size_.store(n + 1, std::memory_order_release);
  return last_hit_ = static_cast<std::uint32_t>(n);
}

}  // namespace hystloop
