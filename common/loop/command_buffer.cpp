#include "loop/command_buffer.hpp"

namespace hystloop {

CommandBuffer::Insert CommandBuffer::insert(const CommandTick& command) noexcept {
  if (command.seq < next_tick_) return Insert::kStale;
  if (command.seq >= next_tick_ + kCapacityTicks) return Insert::kTooFarAhead;
  CommandTick& slot = slots_[slot_of(command.seq)];
  if (slot.seq == command.seq) return Insert::kDuplicate;
  slot = command;
  extend();
  return Insert::kStored;
}

const CommandTick* CommandBuffer::take(std::int64_t k) noexcept {
  if (k < next_tick_) return nullptr;  // not called backwards; nothing to give twice
  next_tick_ = k + 1;
  if (filled_through_ < k) filled_through_ = k;  // ran dry before k: count depth from k + 1
  extend();
  const CommandTick& slot = slots_[slot_of(k)];
  return slot.seq == k ? &slot : nullptr;
}

void CommandBuffer::extend() noexcept {
  while (filled_through_ - next_tick_ + 1 < kCapacityTicks && holds(filled_through_ + 1)) ++filled_through_;
}

void CommandBuffer::clear() noexcept {
  for (CommandTick& c : slots_) c.seq = -1;
  filled_through_ = next_tick_ - 1;
}

}  // namespace hystloop
