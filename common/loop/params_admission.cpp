#include "loop/params_admission.hpp"

#include <limits>
#include <random>

namespace hystloop {

const char* to_string(ParamsRefusal reason) noexcept {
  switch (reason) {
    case ParamsRefusal::invalid: return "invalid";
    case ParamsRefusal::stale: return "stale";
    case ParamsRefusal::refused: return "refused";
  }
  return "unknown";
}

const ParamsAdmission::Row* ParamsAdmission::find(std::int64_t publisher) const noexcept {
  for (std::size_t i = 0; i < used_; ++i) {
    if (rows_[i].publisher == publisher) return &rows_[i];
  }
  return nullptr;
}

ParamsAdmission::Row& ParamsAdmission::row(std::int64_t publisher) noexcept {
  ++use_clock_;
  if (const Row* found = find(publisher)) {
    Row& r = rows_[static_cast<std::size_t>(found - rows_.data())];
    r.last_used = use_clock_;
    return r;
  }
  std::size_t i = used_;
  if (used_ < kPublishers) {
    ++used_;
  } else {
    i = 0;
    for (std::size_t j = 1; j < kPublishers; ++j) {
      if (rows_[j].last_used < rows_[i].last_used) i = j;
    }
    ++evictions_;
  }
  rows_[i] = Row{publisher, 0, 0, use_clock_, 0, 0, 0};
  return rows_[i];
}

bool ParamsAdmission::is_new(std::int64_t publisher, std::int32_t version) const noexcept {
  const Row* r = find(publisher);
  return r == nullptr || version > r->version;
}

void ParamsAdmission::accept(std::int64_t publisher, std::int32_t version) noexcept {
  Row& r = row(publisher);
  if (version > r.version) r.version = version;
  r.below = 0;  // its sets are taken again: not frozen out
}

bool ParamsAdmission::refuse_stale(std::int64_t publisher, std::int32_t version, std::int64_t now_ns) noexcept {
  Row& r = row(publisher);
  if (version >= r.version) return false;  // a repeat of the set accepted: harmless
  // Quiet for longer than the window since the last one: a new run of refusals.
  if (r.below > 0 && now_ns - r.below_ns > kFrozenWindowNs) r.below = 0;
  if (r.below < std::numeric_limits<std::uint32_t>::max()) ++r.below;
  r.below_version = version;
  r.below_ns = now_ns;
  return true;
}

std::size_t ParamsAdmission::frozen(std::int64_t now_ns, FrozenList& out) const noexcept {
  std::size_t n = 0;
  for (std::size_t i = 0; i < used_; ++i) {
    const Row& r = rows_[i];
    if (r.below < kFrozenRefusals || now_ns - r.below_ns > kFrozenWindowNs) continue;
    out[n++] = Frozen{r.publisher, r.below_version, r.version, r.below};
  }
  return n;
}

bool ParamsAdmission::first_refusal(std::int64_t publisher, ParamsRefusal reason) noexcept {
  Row& r = row(publisher);
  const auto bit = static_cast<std::uint8_t>(1u << static_cast<unsigned>(reason));
  const bool first = (r.logged & bit) == 0;
  r.logged = static_cast<std::uint8_t>(r.logged | bit);
  return first;
}

std::int32_t ParamsAdmission::last_version(std::int64_t publisher) const noexcept {
  const Row* r = find(publisher);
  return r == nullptr ? 0 : r->version;
}

std::int64_t new_publisher_id() {
  std::random_device device;
  std::mt19937_64 mix((static_cast<std::uint64_t>(device()) << 32) ^ device());
  std::int64_t id = 0;
  while (id == 0) id = static_cast<std::int64_t>(mix());
  return id;
}

std::int64_t process_publisher_id() {
  static const std::int64_t id = new_publisher_id();
  return id;
}

}  // namespace hystloop
