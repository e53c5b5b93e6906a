#pragma once
// Which HX_PARAMS sets are new: versions are ordered per publisher (mem_params_t.publisher_id),
// never across publishers. A set is stale only when its publisher's last accepted set had the
// same or a higher version; a publisher not in the table (a restarted re-identifier, a new
// hystloop-identify --publish or hystloop-ctl params run, each with a fresh id) is new whatever
// its version, so one huge version from anyone freezes no one else, and a restart is never
// frozen out by the versions it sent before. Publisher id 0 (legacy) is one publisher.
//
// The table is fixed (kPublishers rows, no allocation per message): a new publisher takes a
// free row or the row used least recently (counted: evictions()). An evicted publisher counts
// as new when it comes back. Each row also remembers which refusals were logged for that
// publisher, so the caller logs each reason once per publisher, not once per message.
//
// Frozen out: one forged set with a publisher's own id and a huge version makes every later set
// of that publisher stale, while everything looks healthy. A publisher counts as frozen out
// (frozen(): the receiver reports DEGRADED, naming it) while
//   - at least kFrozenRefusals of its sets were refused as stale with a version BELOW the last
//     one accepted from it, each within kFrozenWindowNs of the one before (a repeat of the
//     accepted version itself is not counted: hystloop-ctl and hystloop-identify send every set
//     several times, and a UDP repeat changes nothing),
//   - the last of them less than kFrozenWindowNs ago (a publisher that goes quiet is cleared), and
//   - none of its sets was accepted since (accepting one clears it).
// Two are needed so that one late datagram overtaken by its successor is not an alarm. Time is
// an argument (a monotonic clock, ns); nothing here reads a clock.

#include <array>
#include <cstddef>
#include <cstdint>

namespace hystloop {

enum class ParamsRefusal : std::uint8_t {
  invalid = 0,  // valid = false: a diagnostic set
  stale = 1,    // not above the last version accepted from the same publisher
  refused = 2,  // failed the receiver's own validation
};
const char* to_string(ParamsRefusal reason) noexcept;

class ParamsAdmission {
 public:
  static constexpr std::size_t kPublishers = 16;
  static constexpr std::uint32_t kFrozenRefusals = 2;
  // 30 s: spans two sets of a re-identifier that publishes every few seconds (it refits every
  // 1 s), and clears half a minute after a publisher went quiet.
  static constexpr std::int64_t kFrozenWindowNs = 30'000'000'000;

  // A publisher frozen out at the time asked (see above).
  struct Frozen {
    std::int64_t publisher = 0;
    std::int32_t refused_version = 0;   // the last version refused as stale
    std::int32_t accepted_version = 0;  // the version its sets must exceed: the last one accepted from it
    std::uint32_t refusals = 0;         // refused below accepted_version in this run (since the last accept)
  };
  using FrozenList = std::array<Frozen, kPublishers>;

  // True when `version` is above the last version accepted from `publisher` (or none was).
  bool is_new(std::int64_t publisher, std::int32_t version) const noexcept;
  // The set was accepted: `publisher`'s versions must now exceed `version`.
  void accept(std::int64_t publisher, std::int32_t version) noexcept;
  // A set from `publisher` was refused for `reason`: true the first time for that publisher
  // and reason (log it), false after.
  bool first_refusal(std::int64_t publisher, ParamsRefusal reason) noexcept;
  // A set from `publisher` was refused as stale (!is_new) at now_ns [ns, monotonic]. True when its
  // version was below the last one accepted from it (it counts toward frozen()), false for a
  // repeat of that version.
  bool refuse_stale(std::int64_t publisher, std::int32_t version, std::int64_t now_ns) noexcept;
  // The publishers frozen out at now_ns [ns, monotonic], in table order, into `out`; returns how many.
  std::size_t frozen(std::int64_t now_ns, FrozenList& out) const noexcept;

  // The last version accepted from `publisher`; 0 when none (or it was evicted).
  std::int32_t last_version(std::int64_t publisher) const noexcept;
  std::size_t publishers() const noexcept { return used_; }
  std::uint64_t evictions() const noexcept { return evictions_; }

 private:
  struct Row {
    std::int64_t publisher = 0;
    std::int32_t version = 0;        // last accepted; 0 = none (versions on the wire are >= 1)
    std::uint8_t logged = 0;         // bit per ParamsRefusal already logged
    std::uint64_t last_used = 0;     // use_clock_ at the last accept or refusal
    std::uint32_t below = 0;         // stale refusals below `version` in the current run (0 after an accept)
    std::int32_t below_version = 0;  // the last of them
    std::int64_t below_ns = 0;       // when it came [ns]
  };
  const Row* find(std::int64_t publisher) const noexcept;
  Row& row(std::int64_t publisher) noexcept;  // finds or makes one (evicting the least recently used)

  std::array<Row, kPublishers> rows_{};
  std::size_t used_ = 0;
  std::uint64_t use_clock_ = 0;
  std::uint64_t evictions_ = 0;
};

// A random non-zero publisher id for mem_params_t.publisher_id (a new one per call).
std::int64_t new_publisher_id();
// This process's: drawn at the first call, the same after (a tool run publishes as one publisher).
std::int64_t process_publisher_id();

}  // namespace hystloop
