#pragma once
// The channels the logger records, each with its counters: a fixed table (no allocation:
// names live in fixed arrays). The rig's channels (common/lcm/channels.hpp) hold the
// first kRigChannels slots from the start, so no other traffic can take their place; other
// channels the subscription lets through get the remaining slots as they appear, and once
// those are gone their messages are counted in UnknownChannels (bounded), not recorded.
// Read by the disk thread (the name, by index) and by the status/summary code.
//
// Threading: the receive-side fields belong to the receiving thread; a slot's name is
// written before the first record that refers to it is pushed through the RecordRing,
// whose release/acquire publishes it to the disk thread. The disk-side counters are
// atomics (relaxed) because the receiving thread reads them for status.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "lcm/channels.hpp"
#include "core/sequence_gap_detector.hpp"
#include "record/record_auth.hpp"
#include "record/unknown_channels.hpp"

namespace hystloop {

// Which channels carry a tick number the logger checks for gaps.
enum class SequenceKind : std::uint8_t { kNone, kSensor, kCommand };

struct ChannelSlot {
  static constexpr std::size_t kMaxName = 63;  // LCM's own limit on a channel name

  std::array<char, kMaxName + 1> name{};
  std::size_t name_length = 0;
  SequenceKind kind = SequenceKind::kNone;
  bool rig = false;  // one of the rig's channels: reported one by one on HX_STATUS

  // Receiving thread.
  std::uint64_t received = 0;
  std::uint64_t bytes_received = 0;
  std::uint64_t dropped_queue_full = 0;  // the disk thread fell behind: the ring was full
  std::uint64_t dropped_oversize = 0;    // larger than the ring's largest record
  std::uint64_t undecodable = 0;  // kind != kNone but not a valid block of that type: recorded, ticks not checked
  // A keyed rig's signed channel: messages whose signature failed, by AuthResult (index 0, kOk,
  // stays 0). Counted in `received`, never recorded nor checked for gaps (record/record_auth.hpp).
  bool verified = false;
  std::array<std::uint64_t, kAuthResults> refused{};
  SequenceGapDetector sequence;

  // Disk thread.
  std::atomic<std::uint64_t> written{0};
  std::atomic<std::uint64_t> bytes_written{0};  // payload bytes
  std::atomic<std::uint64_t> write_failed{0};   // the file refused it (disk full, I/O error)

  std::string_view name_view() const noexcept { return {name.data(), name_length}; }
  std::uint64_t refused_total() const noexcept {
    std::uint64_t n = 0;
    for (const std::uint64_t r : refused) n += r;
    return n;
  }
  std::uint64_t dropped() const noexcept {
    return dropped_queue_full + dropped_oversize + write_failed.load(std::memory_order_relaxed);
  }
};

class ChannelTable {
 public:
  static constexpr std::size_t kMaxChannels = 64;
  static constexpr std::size_t kRigChannels = kChannelSpecs.size();  // slots 0..kRigChannels-1, in kChannelSpecs' order

  // The rig's channels (its sensor and command blocks are checked for gaps), and the
  // SequenceGapDetector settings: a command channel's forward jump after
  // `command_resume_us` of silence is a resume, not a gap (0 = always a gap).
  explicit ChannelTable(const ChannelNames& rig, std::int64_t restart_threshold = 10000,
                        std::int64_t command_resume_us = 0);

  // Receiving thread: the index of `name`, adding a slot for a new one; nullopt when the
  // table is full or the name longer than ChannelSlot::kMaxName (then counted in unknown()).
  std::optional<std::uint32_t> find_or_add(const char* name) noexcept;

  std::size_t size() const noexcept { return size_.load(std::memory_order_acquire); }
  ChannelSlot& operator[](std::size_t i) noexcept { return slots_[i]; }
  const ChannelSlot& operator[](std::size_t i) const noexcept { return slots_[i]; }

  // Messages refused because the table was full or the name too long.
  std::uint64_t unrecorded_channels() const noexcept { return unknown_.messages(); }
  const UnknownChannels& unknown() const noexcept { return unknown_; }

 private:
  std::array<ChannelSlot, kMaxChannels> slots_;
  std::atomic<std::size_t> size_{0};
  std::uint32_t last_hit_ = 0;
  UnknownChannels unknown_;
};

}  // namespace hystloop
