#include "runtime/counter_set.hpp"

namespace hystloop {

void CounterSet::report(StatusReporter& status, const Entries& now) const {
  for (const auto& [name, value] : now) status.counter(name, since(name, value));
}

std::uint64_t CounterSet::since(const std::string& name, std::uint64_t value) const {
  const auto it = baseline_.find(name);
  if (it == baseline_.end() || it->second > value) return value;
  return value - it->second;
}

void CounterSet::rebase(const Entries& now) {
  for (const auto& [name, value] : now) baseline_[name] = value;
}

}  // namespace hystloop
