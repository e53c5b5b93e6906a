#include "lcm/rig_auth.hpp"

#include <utility>

namespace hystloop {
namespace {

std::shared_ptr<const RigAuth>& process_auth_slot() noexcept {
  static std::shared_ptr<const RigAuth> auth;
  return auth;
}

}  // namespace

bool is_authenticated_channel(std::string_view channel) noexcept {
  for (const std::string_view suffix : kAuthenticatedSuffixes) {
    if (channel.size() > suffix.size() && channel.ends_with(suffix) &&
        channel[channel.size() - suffix.size() - 1] == '_') {
      return true;
    }
  }
  return false;
}

std::shared_ptr<const RigAuth> rig_auth_from_key_file(const std::filesystem::path& path, const char* field,
                                                      std::int64_t max_skew_us) {
  auto auth = std::make_shared<RigAuth>();
  auth->key = load_rig_key(path, field);
  auth->max_skew_us = max_skew_us;
  return auth;
}

void set_process_rig_auth(std::shared_ptr<const RigAuth> auth) { process_auth_slot() = std::move(auth); }

std::shared_ptr<const RigAuth> process_rig_auth() noexcept { return process_auth_slot(); }

std::int64_t lcm_body_size(const WireLayout& layout, const void* data, std::size_t size) noexcept {
  const std::int64_t walked = walk_wire_layout(layout, data, size);
  if (walked < 0) return -1;
  const auto body = static_cast<std::size_t>(walked);
  if (body == size) return walked;
  if (size - body == kAuthTrailerBytes && has_auth_magic(static_cast<const unsigned char*>(data) + body, size - body)) {
    return walked;
  }
  return -1;
}

}  // namespace hystloop
