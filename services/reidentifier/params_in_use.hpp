#pragma once
// Which MEM parameter set is "in use" on the rig — the set refit candidates are judged
// against — and which version the next published set gets.
//
// It starts as the configured set (mem.c1/c2/c3) with version 1: the compensator starts from
// the same configuration, and every set published later carries a higher version.
// A set published on HX_PARAMS by anyone else (hystloop-identify --publish, hystloop-ctl params,
// a second re-identifier) becomes the set in use when it is valid and newer (higher version)
// than the set in use: the compensator would switch to it, so candidates must beat it.
// Our own sets come back to us over LCM (same source, a version we published): ignored.
// Every version seen, valid or not, is remembered so the next version is above all of them:
//   version = max(highest seen on HX_PARAMS, ours) + 1.

#include <cstdint>
#include <string>
#include <string_view>

#include "models/mem.hpp"

namespace hystloop {

enum class ParamsOffer : std::uint8_t {
  adopted,  // valid, newer: now the set in use
  echo,     // one we published
  stale,    // not newer than the set in use
  invalid,  // valid = false (diagnostic), or parameters outside the model's domain
};
std::string_view to_string(ParamsOffer offer) noexcept;

class ParamsInUse {
 public:
  static constexpr std::int32_t kInitialVersion = 1;

  ParamsInUse(const MemParams& initial, std::string own_source);  // validates `initial`

  // A set received on HX_PARAMS (already checked against the wire contract).
  ParamsOffer offer(const MemParams& params, std::int32_t version, bool valid, std::string_view source) noexcept;

  // Our accepted candidate becomes the set in use; returns the version to publish it with.
  std::int32_t adopt_own(const MemParams& params) noexcept;
  // A version for a diagnostic (valid = false) set we publish: unique, changes nothing in use.
  std::int32_t claim_version() noexcept;

  const MemParams& params() const noexcept { return params_; }
  std::int32_t version() const noexcept { return version_; }
  std::int32_t highest_seen() const noexcept { return highest_seen_; }
  const std::string& own_source() const noexcept { return own_source_; }
  const std::string& source() const noexcept { return source_; }  // who made the set in use

 private:
  MemParams params_;
  std::int32_t version_ = kInitialVersion;
  std::int32_t highest_seen_ = kInitialVersion;  // over HX_PARAMS and our own
  std::int32_t own_published_ = 0;               // highest version we published
  std::string own_source_;
  std::string source_ = "config";
};

}  // namespace hystloop
