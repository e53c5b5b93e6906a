// Config: listing the keys of the tree and refusing the unknown ones.
#include <algorithm>

#include "core/config.hpp"
#include "core/config_impl.hpp"
#include "core/edit_distance.hpp"

namespace hystloop {
namespace {

void collect_leaves(const YAML::Node& node, const std::string& prefix, std::vector<std::string>& out) {
  if (!node.IsMap() || node.size() == 0) {
    if (!prefix.empty()) out.push_back(prefix);
    return;
  }
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    collect_leaves(kv.second, prefix.empty() ? key : std::string(prefix).append(".").append(key), out);
  }
}

bool starts_with_section(std::string_view key, std::string_view section) {
  return key.size() > section.size() && key.substr(0, section.size()) == section && key[section.size()] == '.';
}

bool is_known(std::string_view key, const std::vector<std::string>& known) {
  for (std::string_view k : known) {
    if (k.size() >= 2 && k.substr(k.size() - 2) == ".*") {
      const auto section = k.substr(0, k.size() - 2);
      if (key == section || starts_with_section(key, section)) return true;
    } else if (key == k || starts_with_section(k, key)) {
      // A leaf that is a parent of a known key (an empty section "bridge:") is fine;
      // get() refuses it if a value is then read through it.
      return true;
    }
  }
  return false;
}

std::string_view last_part(std::string_view key) {
  const auto dot = key.rfind('.');
  return dot == std::string_view::npos ? key : key.substr(dot + 1);
}

// The closest known key: a small edit distance, or the same last part in
// another section ("compensator.u_max_V" for "bridge.u_max_V").
std::string suggestion(std::string_view key, const std::vector<std::string>& known) {
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(2, key.size() / 5) + 1;
  for (std::string_view k : known) {
    if (k.size() >= 2 && k.substr(k.size() - 2) == ".*") continue;
    const std::size_t d = edit_distance(ascii_lower(key), ascii_lower(k));
    if (d < best_distance) {
      best_distance = d;
      best = std::string(k);
    }
  }
  if (!best.empty()) return best;
  for (std::string_view k : known) {
    if (ascii_lower(last_part(k)) == ascii_lower(last_part(key))) return std::string(k);
  }
  return {};
}

}  // namespace

std::vector<std::string> Config::keys() const {
  std::vector<std::string> out;
  collect_leaves(impl_->root, "", out);
  std::sort(out.begin(), out.end());
  return out;
}

void Config::check_no_unknown_keys(const std::vector<std::string>& known) const {
  std::vector<std::string> unknown;
  for (const auto& key : keys()) {
    if (!is_known(key, known)) unknown.push_back(key);
  }
  if (unknown.empty()) return;

  std::string field;
  std::string hints;
  for (const auto& key : unknown) {
    if (!field.empty()) field += ", ";
    field += key;
    const std::string near = suggestion(key, known);
    if (near.empty()) continue;
    hints += hints.empty() ? "; did you mean '" : ", '";
    hints += near + "'";
    if (unknown.size() > 1) hints += " for '" + key + "'";
  }
  const std::string reason =
      (unknown.size() == 1 ? "unknown key" : "unknown keys") + (hints.empty() ? std::string() : hints + "?");
  throw ConfigError(impl_->source_for(unknown.front()), field, reason);
}

}  // namespace hystloop
