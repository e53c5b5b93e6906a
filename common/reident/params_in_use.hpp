#pragma once
// Which MEM parameter set is "in use" on the rig — the set refit candidates are judged
// against — and which version the next published set gets.
//
// It starts as the configured set (mem.c1/c2/c3) with version 1: the compensator starts from
// the same configuration, and every set published later carries a higher version.
// Versions are ordered per publisher (mem_params_t.publisher_id; ours is drawn per start): the
// compensator refuses a set as stale only against the last one it accepted from the same
// publisher (ParamsAdmission), and a set from anyone else (hystloop-identify --publish,
// hystloop-ctl params, a second or restarted re-identifier) becomes the set in use here by the
// same rule when it is valid: the compensator would switch to it, so candidates must beat it.
// Our own sets come back to us over LCM (our publisher id): ignored, whatever set is in use.
// A set with our publisher id and a version we never published is not ours (forged, or another
// process drew the same id): never adopted, counted (forged_sets()), and the service reports
// DEGRADED. Its version is followed like any other seen, so that our next set numbers above it
// and the compensator, which orders versions per publisher id, takes our sets again (one at or
// above kFollowLimit is not followed: the compensator then refuses ours as stale, which it
// reports as a publisher frozen out). Echoes arrive within milliseconds, so the last kSentKept
// versions we published are enough to tell them apart.
// So that the version on HX_COMMAND tells sets apart, ours are numbered above every version
// seen, valid or not (on HX_PARAMS or HX_COMMAND), and above our own:
//   version = max(highest seen, ours) + 1,
// except that a version seen at or above kFollowLimit (2^30: no honest counter gets there) is
// not followed: one huge version from anyone must not run our counter into its ceiling.
//
// HX_COMMAND tells which version the compensator actually applies, per tick (it swaps only at
// a reversal, and a compensator does not repeat the set it uses on HX_PARAMS). Its versions
// count as seen, so a re-identifier started after a set was published (or restarted after
// publishing some) still numbers above the compensator's, which ignores a version not above
// the last it was offered. The applied version at a sample is looked up by tick
// (VersionTimeline): commands run ahead of the samples, so the last block received is not it.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "loop/params_admission.hpp"
#include "models/mem.hpp"
#include "reident/version_timeline.hpp"

namespace hystloop {

enum class ParamsOffer : std::uint8_t {
  adopted,     // valid, newer than its publisher's last: now the set in use
  echo,        // one we published
  stale,       // not newer than the last set adopted from the same publisher
  invalid,     // valid = false (diagnostic), or parameters outside the model's domain
  forged,      // our publisher id, but a version we never published
  other_axis,  // for another axis than the re-identifier's (ReidentCore): another re-identifier's business
};
std::string_view to_string(ParamsOffer offer) noexcept;

class ParamsInUse {
 public:
  static constexpr std::int32_t kInitialVersion = 1;
  static constexpr std::int32_t kUnknownVersion = VersionTimeline::kUnknown;
  static constexpr std::int32_t kFollowLimit = 1 << 30;
  static constexpr std::size_t kSentKept = 64;

  // Validates `initial`. own_publisher_id: the publisher_id our sets carry (non-zero).
  ParamsInUse(const MemParams& initial, std::string own_source, std::int64_t own_publisher_id);

  // A set received on HX_PARAMS (already checked against the wire contract).
  ParamsOffer offer(const MemParams& params, std::int32_t version, std::int64_t publisher_id, bool valid,
                    std::string_view source) noexcept;

  // Our accepted candidate becomes the set in use; returns the version to publish it with.
  std::int32_t adopt_own(const MemParams& params) noexcept;
  // A version for a diagnostic (valid = false) set we publish: unique, changes nothing in use.
  std::int32_t claim_version() noexcept;

  // HX_COMMAND: one command tick (params_version >= 0, checked on the wire), in arrival order.
  void on_command(std::int64_t seq, std::int32_t params_version) noexcept;
  // A sensor tick: returns the version the compensator applied at it, kUnknownVersion when no
  // command at or before it was heard. Ticks come in order: change points before it are forgotten.
  std::int32_t on_sample(std::int64_t seq) noexcept;
  // At the last sample.
  std::int32_t applied_version() const noexcept { return applied_version_; }
  // Version change points dropped because more than VersionTimeline::kCapacity were pending.
  std::uint64_t command_versions_dropped() const noexcept { return applied_.overflows(); }

  const MemParams& params() const noexcept { return params_; }
  std::int32_t version() const noexcept { return version_; }
  // Changes whenever the set in use does (versions of two publishers may be equal).
  std::uint64_t generation() const noexcept { return generation_; }
  std::int64_t own_publisher_id() const noexcept { return own_publisher_id_; }
  // Sets with our publisher id we never published (ParamsOffer::forged), and the last one's version (0: none).
  std::uint64_t forged_sets() const noexcept { return forged_sets_; }
  std::int32_t last_forged_version() const noexcept { return last_forged_version_; }
  // The compensator applies the last of them (HX_COMMAND, at the last sample): under our id, not ours.
  bool forged_applied() const noexcept {
    return forged_sets_ > 0 && applied_version_ != kUnknownVersion && applied_version_ == last_forged_version_;
  }
  std::int32_t highest_seen() const noexcept { return highest_seen_; }
  const std::string& own_source() const noexcept { return own_source_; }
  const std::string& source() const noexcept { return source_; }  // who made the set in use

 private:
  void follow(std::int32_t version) noexcept;           // a version seen: numbering goes above it
  bool published(std::int32_t version) const noexcept;  // one of the last kSentKept versions we claimed

  MemParams params_;
  std::int32_t version_ = kInitialVersion;
  std::int32_t highest_seen_ = kInitialVersion;  // over HX_PARAMS and our own
  std::int32_t own_published_ = 0;               // highest version we published
  std::array<std::int32_t, kSentKept> sent_{};   // the last versions we published (0 = empty), a ring
  std::size_t sent_next_ = 0;
  std::uint64_t forged_sets_ = 0;
  std::int32_t last_forged_version_ = 0;
  std::uint64_t generation_ = 0;
  std::int64_t own_publisher_id_;
  ParamsAdmission admission_;  // the last version adopted, per publisher
  std::string own_source_;
  std::string source_ = "config";
  VersionTimeline applied_;
  std::int32_t applied_version_ = kUnknownVersion;
};

}  // namespace hystloop
