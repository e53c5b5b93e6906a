#include "auth/rig_key.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include <sodium.h>

#include "auth/sodium_init.hpp"
#include "core/errors.hpp"

namespace hystloop {
namespace {

static_assert(kRigKeyBytes == crypto_auth_KEYBYTES, "the rig key is a crypto_auth key");

constexpr std::size_t kHexDigits = 2 * kRigKeyBytes;

[[noreturn]] void refuse(const char* field, const std::filesystem::path& path, const std::string& reason) {
  throw ParameterError(field, path.string() + ": " + reason);
}

std::string mode_string(mode_t mode) {
  char text[8];
  std::snprintf(text, sizeof text, "%04o", static_cast<unsigned>(mode & 07777));
  return text;
}

}  // namespace

RigKey load_rig_key(const std::filesystem::path& path, const char* field) {
  ensure_sodium();
  if (path.empty()) throw ParameterError(field, "empty path");
  const std::string keygen = "create one with `hystloop-ctl keygen --out " + path.string() + "`";
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    refuse(field, path, std::string(std::strerror(errno)) + " (" + keygen + ")");
  }
  if (!S_ISREG(st.st_mode)) refuse(field, path, "not a regular file");
  if ((st.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    refuse(field, path,
           "the rig key is readable or writable by group or others (mode " + mode_string(st.st_mode) +
               "): anyone who can read it can move the stage; run `chmod 600 " + path.string() + "`");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) refuse(field, path, "cannot be read (" + std::string(std::strerror(errno)) + ")");
  std::ostringstream content;
  content << in.rdbuf();
  std::string text = content.str();
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  if (text.size() != kHexDigits) {
    refuse(field, path,
           "expected " + std::to_string(kHexDigits) + " hex digits (a key from hystloop-ctl keygen), got " +
               std::to_string(text.size()) + " characters; " + keygen);
  }
  RigKey key;
  std::size_t written = 0;
  const char* end = nullptr;
  if (sodium_hex2bin(key.bytes.data(), key.bytes.size(), text.data(), text.size(), nullptr, &written, &end) != 0 ||
      written != kRigKeyBytes || end != text.data() + text.size()) {
    sodium_memzero(text.data(), text.size());
    refuse(field, path, "not a hexadecimal key; " + keygen);
  }
  sodium_memzero(text.data(), text.size());
  return key;
}

RigKey generate_rig_key() {
  ensure_sodium();
  RigKey key;
  crypto_auth_keygen(key.bytes.data());
  return key;
}

void write_rig_key(const std::filesystem::path& path, const RigKey& key, bool overwrite) {
  const char* field = "--out";
  if (path.empty()) throw ParameterError(field, "empty path");
  std::array<char, kHexDigits + 2> hex{};
  sodium_bin2hex(hex.data(), kHexDigits + 1, key.bytes.data(), key.bytes.size());
  hex[kHexDigits] = '\n';

  int flags = O_WRONLY | O_CREAT | O_CLOEXEC | O_NOFOLLOW;
  flags |= overwrite ? O_TRUNC : O_EXCL;
  const int fd = ::open(path.c_str(), flags, 0600);
  if (fd < 0) {
    if (errno == EEXIST)
      refuse(field, path, "exists; pass --force to replace the rig's key (every host then needs the new one)");
    refuse(field, path, std::strerror(errno));
  }
  // An overwritten file keeps its mode: make it 0600 before the key goes in.
  bool ok = ::fchmod(fd, 0600) == 0;
  const ssize_t n = ok ? ::write(fd, hex.data(), kHexDigits + 1) : -1;
  ok = ok && n == static_cast<ssize_t>(kHexDigits + 1);
  const int saved = errno;
  ok = (::close(fd) == 0) && ok;
  sodium_memzero(hex.data(), hex.size());
  if (!ok) refuse(field, path, std::string("could not write the key (") + std::strerror(saved) + ")");
}

}  // namespace hystloop
