#pragma once
// The rig's secret key: 32 random bytes (libsodium's crypto_auth_KEYBYTES) shared by every
// process that may move the stage, kept in a file readable only by its owner. The file holds
// the key as 64 hexadecimal digits (and an optional newline), so it survives being copied
// between the hosts of a rig by any means.
//
// Loading refuses, with a message naming the path and the fix:
//   a missing or unreadable file, a file that is not a regular file,
//   a file whose mode lets group or others read or write it ("chmod 600 PATH"),
//   content that is not exactly 64 hex digits.

#include <array>
#include <cstddef>
#include <filesystem>

namespace hystloop {

inline constexpr std::size_t kRigKeyBytes = 32;

struct RigKey {
  std::array<unsigned char, kRigKeyBytes> bytes{};
};

// Throws ParameterError(field, "<path>: <reason>; <fix>"). `field` names the setting the path
// came from ("auth.key_file", "--key-file").
RigKey load_rig_key(const std::filesystem::path& path, const char* field = "auth.key_file");

// Draws a new key from libsodium's CSPRNG.
RigKey generate_rig_key();

// Writes `key` to `path` with mode 0600 (created with that mode: never readable by others, not
// even for a moment). Refuses an existing file unless `overwrite`. Throws ParameterError
// ("--out") when the file exists or cannot be written.
void write_rig_key(const std::filesystem::path& path, const RigKey& key, bool overwrite);

}  // namespace hystloop
