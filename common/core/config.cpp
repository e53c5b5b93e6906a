#include "core/config.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <type_traits>

#include "core/config_impl.hpp"
#include "core/edit_distance.hpp"

namespace hystloop {
namespace {

const std::string kOverrideSource = "--set";

std::string compose(const std::string& source, const std::string& field, const std::string& reason) {
  return field.empty() ? source + ": " + reason : source + ": " + field + ": " + reason;
}

// How a node that was not what we wanted looks, for "expected X, got Y".
std::string describe(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar: return "'" + node.Scalar() + "'";
    case YAML::NodeType::Sequence: return "a list";
    case YAML::NodeType::Map: return "a map";
    default: return "no value";
  }
}

// yaml-cpp keeps every entry of a map with a repeated key but answers a lookup with the first,
// so a second `u_max_V:` further down a file would be silently ignored. Refused instead, naming
// the key and both lines. `prefix` is the dotted path of `node`.
void refuse_duplicate_keys(const YAML::Node& node, const std::string& source, const std::string& prefix) {
  if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) {
      refuse_duplicate_keys(node[i], source, prefix + "[" + std::to_string(i) + "]");
    }
    return;
  }
  if (!node.IsMap()) return;
  std::map<std::string, int> first_line;  // key -> its line (1-based)
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string key = it->first.IsScalar() ? it->first.Scalar() : describe(it->first);
    const std::string path = prefix.empty() ? key : std::string(prefix).append(".").append(key);
    const int line = it->first.Mark().line + 1;
    const auto [seen, inserted] = first_line.emplace(key, line);
    if (!inserted) {
      throw ConfigError(source, path,
                        "duplicate key at line " + std::to_string(line) + " (first at line " +
                            std::to_string(seen->second) + "): remove one of them");
    }
    refuse_duplicate_keys(it->second, source, path);
  }
}

// Walks `parts` from `node`; nullopt when a key is absent (or its parent is an
// empty section). Recursion, because assigning a YAML::Node would rewrite the tree.
std::optional<YAML::Node> find_node(const Config& cfg, const YAML::Node& node, const std::vector<std::string>& parts,
                                    std::size_t i, std::string& walked) {
  if (i == parts.size()) return node;
  if (node.IsNull()) return std::nullopt;
  if (!node.IsMap()) cfg.fail(walked, "expected a map, got " + describe(node));
  const YAML::Node child = node[parts[i]];
  if (!child.IsDefined()) return std::nullopt;
  walked += walked.empty() ? parts[i] : "." + parts[i];
  return find_node(cfg, child, parts, i + 1, walked);
}

void set_node(YAML::Node node, const std::vector<std::string>& parts, std::size_t i, const YAML::Node& value,
              std::string& walked) {
  if (!node.IsMap()) {
    if (!node.IsDefined() || node.IsNull()) {
      node = YAML::Node(YAML::NodeType::Map);  // assigns into the tree: creates the section
    } else {
      throw ConfigError(kOverrideSource, walked, "cannot set a key inside it: it is " + describe(node) + ", not a map");
    }
  }
  walked += walked.empty() ? parts[i] : "." + parts[i];
  YAML::Node child = node[parts[i]];
  if (i + 1 == parts.size()) {
    child = value;
  } else {
    set_node(child, parts, i + 1, value, walked);
  }
}

void require_valid_path(const Config& cfg, std::string_view path, const std::vector<std::string>& parts) {
  for (const auto& p : parts) {
    if (p.empty()) cfg.fail(path, "malformed key (empty part between dots)");
  }
}

template <class T>
T convert_scalar(const Config& cfg, const YAML::Node& node, const std::string& field) {
  if constexpr (std::is_same_v<T, std::string>) {
    if (!node.IsScalar()) cfg.fail(field, "expected a string, got " + describe(node));
    return node.Scalar();
  } else {
    const char* expected = std::is_same_v<T, bool>     ? "expected true or false"
                           : std::is_same_v<T, double> ? "expected a number"
                                                       : "expected an integer";
    T value{};
    if (!node.IsScalar() || !YAML::convert<T>::decode(node, value)) {
      cfg.fail(field, std::string(expected) + ", got " + describe(node));
    }
    if constexpr (std::is_same_v<T, double>) {
      if (!std::isfinite(value)) cfg.fail(field, "must be a finite number (got " + node.Scalar() + ")");
    }
    return value;
  }
}

template <class T>
T convert_value(const Config& cfg, const YAML::Node& node, const std::string& field) {
  if constexpr (std::is_same_v<T, std::vector<double>> || std::is_same_v<T, std::vector<std::string>>) {
    if (!node.IsSequence()) cfg.fail(field, "expected a list, got " + describe(node));
    T out;
    out.reserve(node.size());
    for (std::size_t i = 0; i < node.size(); ++i) {
      out.push_back(convert_scalar<typename T::value_type>(cfg, node[i], field + "[" + std::to_string(i) + "]"));
    }
    return out;
  } else {
    return convert_scalar<T>(cfg, node, field);
  }
}

std::string join_fields(const std::vector<std::string>& fields) {
  std::string out;
  for (const auto& f : fields) out += (out.empty() ? "" : ", ") + f;
  return out;
}

// The field a misspelt key meant, or empty when none is close.
std::string closest_key(const std::string& key, const std::vector<std::string>& fields) {
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(2, key.size() / 5) + 1;
  for (const auto& f : fields) {
    const std::size_t d = edit_distance(ascii_lower(key), ascii_lower(f));
    if (d < best_distance) {
      best_distance = d;
      best = f;
    }
  }
  return best;
}

}  // namespace

ConfigError::ConfigError(std::string source, std::string field, const std::string& reason)
    : ParameterError(std::move(field), reason),
      source_(std::move(source)),
      message_(compose(source_, this->field(), reason)) {}

const std::string& Config::Impl::source_for(std::string_view path) const {
  for (auto it = overridden.rbegin(); it != overridden.rend(); ++it) {  // the last one set it
    const std::string& key = it->first;
    // A key below it, or an entry of its list ("gains[1]"), came from the same place.
    if (path == key || (path.size() > key.size() && path.substr(0, key.size()) == key &&
                        (path[key.size()] == '.' || path[key.size()] == '['))) {
      return it->second;
    }
  }
  return source;
}

std::vector<std::string> split_config_path(std::string_view path) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = path.find('.', start);
    parts.emplace_back(path.substr(start, dot == std::string_view::npos ? dot : dot - start));
    if (dot == std::string_view::npos) return parts;
    start = dot + 1;
  }
}

Config::Config() : impl_(std::make_unique<Impl>()) {}
Config::Config(const Config& other) : impl_(std::make_unique<Impl>(*other.impl_)) {
  impl_->root.reset(YAML::Clone(other.impl_->root));  // reset(): `=` would write into `other`
}
Config& Config::operator=(const Config& other) {
  if (this != &other) *this = Config(other);
  return *this;
}
Config::Config(Config&&) noexcept = default;
Config& Config::operator=(Config&&) noexcept = default;
Config::~Config() = default;

Config Config::from_string(std::string_view yaml_text, std::string source_name) {
  Config cfg;
  cfg.impl_->source = std::move(source_name);
  YAML::Node root;
  try {
    root = YAML::Load(std::string(yaml_text));
  } catch (const YAML::ParserException& e) {
    throw ConfigError(
        cfg.impl_->source, "",
        "line " + std::to_string(e.mark.line + 1) + ", column " + std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
  if (root.IsNull() || !root.IsDefined()) return cfg;  // empty file: empty map
  refuse_duplicate_keys(root, cfg.impl_->source, "");
  if (!root.IsMap()) {
    throw ConfigError(cfg.impl_->source, "", "the top level must be a map of keys, got " + describe(root));
  }
  cfg.impl_->root.reset(root);
  return cfg;
}

Config Config::load_file(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::FILE* f = std::fopen(name.c_str(), "rb");
  if (f == nullptr) throw ConfigError(name, "", "cannot open file");
  std::string text;
  char buf[4096];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) throw ConfigError(name, "", "cannot read file");
  return from_string(text, name);
}

const std::string& Config::source() const noexcept { return impl_->source; }

const std::string& Config::source_of(std::string_view path) const { return impl_->source_for(path); }

void Config::fail(std::string_view path, const std::string& reason) const {
  throw ConfigError(impl_->source_for(path), std::string(path), reason);
}

bool Config::has(std::string_view path) const {
  const auto parts = split_config_path(path);
  require_valid_path(*this, path, parts);
  std::string walked;
  return find_node(*this, impl_->root, parts, 0, walked).has_value();
}

template <ConfigValue T>
T Config::get(std::string_view path, const T& default_value) const {
  const auto parts = split_config_path(path);
  require_valid_path(*this, path, parts);
  std::string walked;
  const auto node = find_node(*this, impl_->root, parts, 0, walked);
  if (!node) return default_value;
  const std::string field(path);
  if constexpr (std::is_same_v<T, int>) {
    const auto wide = convert_value<std::int64_t>(*this, *node, field);
    if (wide < std::numeric_limits<int>::min() || wide > std::numeric_limits<int>::max()) {
      fail(path, "out of range for an int (got " + std::to_string(wide) + ")");
    }
    return static_cast<int>(wide);
  } else {
    return convert_value<T>(*this, *node, field);
  }
}

template <ConfigValue T>
T Config::get(std::string_view path) const {
  if (!has(path)) fail(path, "required but missing");
  return get<T>(path, T{});
}

double Config::get_in_range(std::string_view path, double default_value, double lo, double hi) const {
  const double v = get<double>(path, default_value);
  if (!(v >= lo && v <= hi)) {
    fail(path, "must be in [" + number_text(lo) + ", " + number_text(hi) + "] (got " + number_text(v) + ")");
  }
  return v;
}

double Config::get_positive(std::string_view path, double default_value) const {
  const double v = get<double>(path, default_value);
  try {
    require_positive(path, v);
  } catch (const ParameterError& e) {
    fail(path, e.reason());
  }
  return v;
}

double Config::get_non_negative(std::string_view path, double default_value) const {
  const double v = get<double>(path, default_value);
  try {
    require_non_negative(path, v);
  } catch (const ParameterError& e) {
    fail(path, e.reason());
  }
  return v;
}

std::int64_t Config::get_int_in_range(std::string_view path, std::int64_t default_value, std::int64_t lo,
                                      std::int64_t hi) const {
  const auto v = get<std::int64_t>(path, default_value);
  if (v < lo || v > hi) {
    fail(path, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "] (got " + std::to_string(v) + ")");
  }
  return v;
}

namespace {
// The list at `path` (nothing when absent); anything else is refused naming it.
std::optional<YAML::Node> find_list(const Config& cfg, const YAML::Node& root, std::string_view path,
                                    const std::string& of_what) {
  const auto parts = split_config_path(path);
  require_valid_path(cfg, path, parts);
  std::string walked;
  auto node = find_node(cfg, root, parts, 0, walked);
  if (node && !node->IsSequence()) cfg.fail(path, "expected a list of " + of_what + ", got " + describe(*node));
  return node;
}
}  // namespace

std::vector<std::vector<double>> Config::get_rows(std::string_view path, std::size_t width) const {
  const auto node = find_list(*this, impl_->root, path, "lists");
  if (!node) return {};
  const std::string field(path);
  std::vector<std::vector<double>> out;
  out.reserve(node->size());
  for (std::size_t i = 0; i < node->size(); ++i) {
    const std::string entry = field + "[" + std::to_string(i) + "]";
    auto row = convert_value<std::vector<double>>(*this, (*node)[i], entry);
    if (width > 0 && row.size() != width) {
      fail(entry, "expected " + std::to_string(width) + " numbers, got " + std::to_string(row.size()));
    }
    if (row.empty()) fail(entry, "expected at least one number, got an empty list");
    out.push_back(std::move(row));
  }
  return out;
}

std::vector<std::vector<double>> Config::get_records(std::string_view path,
                                                     const std::vector<std::string>& fields) const {
  const auto node = find_list(*this, impl_->root, path, "maps");
  if (!node) return {};
  const std::string field(path);
  std::vector<std::vector<double>> out;
  out.reserve(node->size());
  for (std::size_t i = 0; i < node->size(); ++i) {
    const std::string entry = field + "[" + std::to_string(i) + "]";
    const YAML::Node item = (*node)[i];
    if (!item.IsMap()) fail(entry, "expected a map of " + join_fields(fields) + ", got " + describe(item));
    std::vector<double> row(fields.size(), std::numeric_limits<double>::quiet_NaN());
    for (const auto& kv : item) {
      const std::string key = kv.first.as<std::string>();
      const auto at = std::find(fields.begin(), fields.end(), key);
      if (at == fields.end()) {
        const std::string near = closest_key(key, fields);
        std::string why = "unknown key";
        if (near.empty()) {
          why += " (expected ";
          why += join_fields(fields);
          why += ")";
        } else {
          why += "; did you mean '";
          why += near;
          why += "'?";
        }
        std::string at_key = entry;
        at_key += ".";
        at_key += key;
        fail(at_key, why);
      }
      std::string at_field = entry;
      at_field += ".";
      at_field += key;
      row[static_cast<std::size_t>(at - fields.begin())] = convert_scalar<double>(*this, kv.second, at_field);
    }
    out.push_back(std::move(row));
  }
  return out;
}

void Config::apply_override(std::string_view assignment) {
  const std::size_t eq = assignment.find('=');
  if (eq == std::string_view::npos || eq == 0) {
    throw ConfigError(kOverrideSource, "", "expected key=value, got '" + std::string(assignment) + "'");
  }
  const std::string key(assignment.substr(0, eq));
  const std::string text(assignment.substr(eq + 1));
  const auto parts = split_config_path(key);
  for (const auto& p : parts) {
    if (p.empty()) throw ConfigError(kOverrideSource, key, "malformed key (empty part between dots)");
  }
  YAML::Node value;
  try {
    value = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(kOverrideSource, key, "cannot parse value '" + text + "': " + e.msg);
  }
  refuse_duplicate_keys(value, kOverrideSource, key);
  std::string walked;
  set_node(impl_->root, parts, 0, value, walked);
  impl_->overridden.emplace_back(key, kOverrideSource);
}

namespace {

// Merges `layer` into `node` (both maps): a map into a map key by key, anything else (a value, a
// list) replacing what was there whole, so a layer's list of modes is the list, never a mix.
void merge_map(YAML::Node node, const YAML::Node& layer) {
  for (const auto& kv : layer) {
    const std::string key = kv.first.as<std::string>();
    YAML::Node child = node[key];
    if (kv.second.IsMap() && child.IsMap()) {
      merge_map(child, kv.second);
    } else {
      child = YAML::Clone(kv.second);
    }
  }
}

}  // namespace

void Config::layer(const Config& other) {
  merge_map(impl_->root, other.impl_->root);
  for (std::string& key : other.keys()) impl_->overridden.emplace_back(std::move(key), other.impl_->source);
  for (const auto& o : other.impl_->overridden) impl_->overridden.push_back(o);
}

void Config::apply_overrides(const std::vector<std::string>& assignments) {
  for (const auto& a : assignments) apply_override(a);
}

std::string Config::dump() const {
  YAML::Emitter out;
  out << impl_->root;
  return out.c_str();
}

#define HYSTLOOP_CONFIG_INSTANTIATE(T)                         \
  template T Config::get<T>(std::string_view, const T&) const; \
  template T Config::get<T>(std::string_view) const;
HYSTLOOP_CONFIG_INSTANTIATE(bool)
HYSTLOOP_CONFIG_INSTANTIATE(int)
HYSTLOOP_CONFIG_INSTANTIATE(std::int64_t)
HYSTLOOP_CONFIG_INSTANTIATE(double)
HYSTLOOP_CONFIG_INSTANTIATE(std::string)
HYSTLOOP_CONFIG_INSTANTIATE(std::vector<double>)
HYSTLOOP_CONFIG_INSTANTIATE(std::vector<std::string>)
#undef HYSTLOOP_CONFIG_INSTANTIATE

}  // namespace hystloop
