#pragma once
// libsodium's one-time initialisation (thread-safe, idempotent). Throws std::runtime_error if
// the library cannot initialise (no entropy source).

namespace hystloop {

void ensure_sodium();

}  // namespace hystloop
