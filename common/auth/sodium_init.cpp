#include "auth/sodium_init.hpp"

#include <stdexcept>

#include <sodium.h>

namespace hystloop {

void ensure_sodium() {
  if (sodium_init() < 0) throw std::runtime_error("libsodium could not initialise (no entropy source?)");
}

}  // namespace hystloop
