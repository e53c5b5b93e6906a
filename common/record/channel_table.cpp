#include "record/channel_table.hpp"

#include <cstring>
#include <string>

#include "core/errors.hpp"

namespace hystloop {

namespace {
void set_name(ChannelSlot& slot, const char* name, std::size_t length) noexcept {
  std::memcpy(slot.name.data(), name, length);
  slot.name[length] = '\0';
  slot.name_length = length;
}
}  // namespace

ChannelTable::ChannelTable(const ChannelNames& rig, std::int64_t restart_threshold, std::int64_t command_resume_us)
    : slots_() {
  const SequenceGapDetector detector(restart_threshold);  // validates both settings
  const SequenceGapDetector command_detector(restart_threshold, command_resume_us);
  for (auto& slot : slots_) slot.sequence = detector;
  static_assert(kRigChannels < kMaxChannels);
  for (std::size_t i = 0; i < kRigChannels; ++i) {
    const std::string name = rig.prefix + std::string(kChannelSpecs[i].suffix);
    if (name.size() > ChannelSlot::kMaxName) {  // cannot happen: the prefix has <= 32 characters
      throw ParameterError("rig.prefix", "makes channel names longer than " + std::to_string(ChannelSlot::kMaxName));
    }
    ChannelSlot& slot = slots_[i];
    set_name(slot, name.c_str(), name.size());
    slot.rig = true;
    if (name == rig.sensor) slot.kind = SequenceKind::kSensor;
    if (name == rig.command) {
      slot.kind = SequenceKind::kCommand;
      slot.sequence = command_detector;
    }
  }
  size_.store(kRigChannels, std::memory_order_release);
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
    unknown_.count(name, length);
    return std::nullopt;
  }
  set_name(slots_[n], name, length);
  size_.store(n + 1, std::memory_order_release);
  return last_hit_ = static_cast<std::uint32_t>(n);
}

}  // namespace hystloop
