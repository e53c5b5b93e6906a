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

  // True when `version` is above the last version accepted from `publisher` (or none was).
  bool is_new(std::int64_t publisher, std::int32_t version) const noexcept;
  // The set was accepted: `publisher`'s versions must now exceed `version`.
  void accept(std::int64_t publisher, std::int32_t version) noexcept;
  // A set from `publisher` was refused for `reason`: true the first time for that publisher
  // and reason (log it), false after.
  bool first_refusal(std::int64_t publisher, ParamsRefusal reason) noexcept;

  // The last version accepted from `publisher`; 0 when none (or it was evicted).
  std::int32_t last_version(std::int64_t publisher) const noexcept;
  std::size_t publishers() const noexcept { return used_; }
  std::uint64_t evictions() const noexcept { return evictions_; }

 private:
  struct Row {
    std::int64_t publisher = 0;
    std::int32_t version = 0;     // last accepted; 0 = none (versions on the wire are >= 1)
    std::uint8_t logged = 0;      // bit per ParamsRefusal already logged
    std::uint64_t last_used = 0;  // use_clock_ at the last accept or refusal
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
