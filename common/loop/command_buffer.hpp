#pragma once
// The bridge's jitter buffer: commands the compensator sent ahead of time, indexed by the tick
// they are meant for. The I/O side inserts whatever arrives (in order or not, repeated or not);
// the clock takes the command of tick k at tick k. Fixed capacity, no allocation, no lock: it
// lives on the real-time thread, fed through an SPSC queue.
//
// Depth is the run-ahead margin: the number of consecutive ticks buffered after the last tick
// taken. A depth of 0 means the next tick will be late unless a command arrives in time.

#include <array>
#include <cstdint>

#include "core/ticks.hpp"

namespace hystloop {

class CommandBuffer {
 public:
  static constexpr std::int64_t kCapacityTicks = 8192;  // 0.82 s at 10 kHz: the longest horizon it takes

  enum class Insert : std::uint8_t {
    kStored,       // buffered for its tick
    kDuplicate,    // that tick already has a command: the first one stays (a tick is decided once)
    kStale,        // its tick has been taken already
    kTooFarAhead,  // beyond kCapacityTicks after the next tick
  };

  // Inserts a command (its values are the caller's to check).
  Insert insert(const CommandTick& command) noexcept;

  // The command for tick k, or nullptr when none arrived (late). Ticks before k are dropped;
  // k must not decrease between calls.
  const CommandTick* take(std::int64_t k) noexcept;

  // Next tick take() expects.
  std::int64_t next_tick() const noexcept { return next_tick_; }
  // Consecutive ticks buffered from next_tick() on.
  std::int64_t depth() const noexcept { return filled_through_ - next_tick_ + 1; }
  // A command for tick k waits (take(k) would return it).
  bool has(std::int64_t k) const noexcept { return k >= next_tick_ && holds(k); }
  // Drops everything buffered (the ticks taken so far stay taken).
  void clear() noexcept;

 private:
  static std::size_t slot_of(std::int64_t seq) noexcept { return static_cast<std::size_t>(seq % kCapacityTicks); }
  bool holds(std::int64_t seq) const noexcept { return slots_[slot_of(seq)].seq == seq; }
  void extend() noexcept;

  std::array<CommandTick, kCapacityTicks> slots_ = make_empty();
  std::int64_t next_tick_ = 0;
  std::int64_t filled_through_ = -1;  // last tick t with every tick in [next_tick_, t] buffered

  static std::array<CommandTick, kCapacityTicks> make_empty() noexcept {
    std::array<CommandTick, kCapacityTicks> a{};
    for (CommandTick& c : a) c.seq = -1;
    return a;
  }
};

}  // namespace hystloop
