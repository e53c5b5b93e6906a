#pragma once
// Which channels a keyed rig signs, the rig's key and skew as the LCM endpoints use them, and
// where a received message's LCM encoding ends when an authentication trailer may follow it
// (auth/message_auth.hpp has the format).
//
// Publisher and Subscription take a RigAuth (nullptr = keyless); by default they take the
// process's, which a program's main sets once from its configuration before it makes any
// endpoint (set_process_rig_auth). An endpoint reads it once, at construction.

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string_view>

#include "auth/message_auth.hpp"
#include "auth/rig_key.hpp"
#include "lcm/channels.hpp"
#include "lcm/wire_layout.hpp"

namespace hystloop {

// Channels whose messages can move the stage or change what it does: signed on a keyed rig,
// refused unsigned. HX_SENSOR is one of them: the compensator plans from its tick numbers and
// the re-identifier fits its samples, so a forged block moves the plan. HX_STATUS is not: it
// only reports (docs/SECURITY.md).
inline constexpr std::array<std::string_view, 7> kAuthenticatedSuffixes{
    kCommandSuffix, kControlSuffix, kTrajectorySuffix, kScanSuffix, kParamsSuffix, kModelSuffix, kSensorSuffix};

// True if `channel` is <prefix><suffix> for one of kAuthenticatedSuffixes (the prefix ends in '_').
bool is_authenticated_channel(std::string_view channel) noexcept;

inline constexpr double kDefaultMaxSkew_s = 2.0;

struct RigAuth {
  RigKey key;
  std::int64_t max_skew_us = static_cast<std::int64_t>(kDefaultMaxSkew_s * 1e6);
};

// The key from `path` (auth/rig_key.hpp: throws ParameterError naming `field`) with that skew.
std::shared_ptr<const RigAuth> rig_auth_from_key_file(const std::filesystem::path& path, const char* field,
                                                      std::int64_t max_skew_us = RigAuth{}.max_skew_us);

// The process's rig authentication (nullptr = keyless, the default). Set it before any thread
// or endpoint is made.
void set_process_rig_auth(std::shared_ptr<const RigAuth> auth);
std::shared_ptr<const RigAuth> process_rig_auth() noexcept;

// The size of the LCM encoding at the start of data[0..size) (walked by `layout`) when the
// message is exactly that encoding or that encoding followed by an authentication trailer;
// -1 when the walk fails or other bytes follow. A reader that does not check signatures uses
// this and ignores the trailer.
std::int64_t lcm_body_size(const WireLayout& layout, const void* data, std::size_t size) noexcept;

}  // namespace hystloop
