#pragma once
// Service configuration: a YAML file read into a tree, typed values read by
// dotted path with defaults, `--set key=value` overrides merged over the file,
// and refusal with a message that names the file, the field and the reason:
//
//   auto cfg = Config::load_file("bridge.yaml");
//   cfg.apply_overrides(cli_sets);                        // e.g. {"bridge.u_max_V=120"}
//   cfg.check_no_unknown_keys({"bridge.u_max_V", "bridge.noise_rms_m", "logger.*"});
//   const double u_max = cfg.get_positive("bridge.u_max_V", 250.0);
//   const double noise = cfg.get_in_range("bridge.noise_rms_m", 1e-9, 0, 1e-6);
//
//   -> ConfigError "bridge.yaml: bridge.u_max_V: must be > 0 (got -5)"
//   -> ConfigError "bridge.yaml: bridge.u_max_V: expected a number, got 'abc'"
//   -> ConfigError "bridge.yaml: bridge.u_maxV: unknown key; did you mean 'bridge.u_max_V'?"
//
// A value that came from --set is reported with "--set" in place of the file.
// A key that is absent gives the default; a key present with no value is refused.
// Numbers must be finite (.inf/.nan are refused). Keys may not contain dots.
// Config is read at start-up, never on the per-sample path.

#include <concepts>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/errors.hpp"

namespace hystloop {

// A refused configuration value. what() is "<source>: <field>: <reason>" (the
// field part is left out when empty, e.g. for a YAML syntax error).
class ConfigError : public ParameterError {
 public:
  ConfigError(std::string source, std::string field, const std::string& reason);
  const char* what() const noexcept override { return message_.c_str(); }
  const std::string& source() const noexcept { return source_; }

 private:
  std::string source_;
  std::string message_;
};

// The value types get<T>() reads.
template <class T>
concept ConfigValue =
    std::same_as<T, bool> || std::same_as<T, int> || std::same_as<T, std::int64_t> || std::same_as<T, double> ||
    std::same_as<T, std::string> || std::same_as<T, std::vector<double>> || std::same_as<T, std::vector<std::string>>;

class Config {
 public:
  Config();                     // empty tree, source "<empty>"
  Config(const Config& other);  // deep copy: overriding a copy leaves the original alone
  Config& operator=(const Config& other);
  Config(Config&&) noexcept;
  Config& operator=(Config&&) noexcept;
  ~Config();

  // Throws ConfigError naming the file when it cannot be read or parsed, or when
  // its top level is not a map. An empty file is an empty map.
  static Config load_file(const std::filesystem::path& path);
  static Config from_string(std::string_view yaml_text, std::string source_name = "<string>");

  // The file name as given (or the source name of from_string()).
  const std::string& source() const noexcept;
  // Where `path`'s value came from: the layer or --set that last gave it, else source().
  const std::string& source_of(std::string_view path) const;
  // True when the key is present (even with no value).
  bool has(std::string_view path) const;

  // The value at `path`, or `default_value` when absent.
  template <ConfigValue T>
  T get(std::string_view path, const T& default_value) const;
  // The value at `path`; refused ("required but missing") when absent.
  template <ConfigValue T>
  T get(std::string_view path) const;

  // Numbers with a range check (the default must satisfy it too).
  double get_in_range(std::string_view path, double default_value, double lo, double hi) const;
  double get_positive(std::string_view path, double default_value) const;
  double get_non_negative(std::string_view path, double default_value) const;
  std::int64_t get_int_in_range(std::string_view path, std::int64_t default_value, std::int64_t lo,
                                std::int64_t hi) const;

  // A list of rows of numbers, [[1, 2], [3, 4]] (a lab's [[re, im], ...] roots): each row a list of
  // `width` numbers (any length >= 1 when width is 0). Absent: empty. A refusal names the entry
  // ("stage.poles[1]: expected 2 numbers, got 3").
  std::vector<std::vector<double>> get_rows(std::string_view path, std::size_t width = 0) const;
  // A list of maps of numbers, [{frequency_hz: 780, damping_ratio: 0.03}, ...]: each entry's keys
  // among `fields` (an unknown one refused naming it, "modes[0].dampin_ratio", with the one meant),
  // each entry's value NaN for a field it does not give (the caller refuses or defaults it). Absent:
  // empty.
  std::vector<std::vector<double>> get_records(std::string_view path, const std::vector<std::string>& fields) const;

  // Merges one "dotted.key=value" over the tree; the value is parsed as YAML
  // ("3" a number, "[1, 2]" a list, "abc" a string). Intermediate maps are created.
  // Throws ConfigError (source "--set") for a malformed assignment.
  void apply_override(std::string_view assignment);
  void apply_overrides(const std::vector<std::string>& assignments);
  // Merges another file's tree over this one (a scenario's or a rig's settings over a service's
  // config): maps key by key, a value or a list replacing the one here whole. Errors about a key
  // the layer gave name the layer's file.
  void layer(const Config& other);

  // Throws ConfigError listing every key of the tree that is not in `known`,
  // with a "did you mean" suggestion when one is close. An entry "section.*"
  // accepts anything under section (e.g. a section read by another process).
  void check_no_unknown_keys(const std::vector<std::string>& known) const;

  // Every leaf key (dotted) of the tree, sorted.
  std::vector<std::string> keys() const;
  // The merged tree as YAML, for logging the effective configuration.
  std::string dump() const;

  // Throws ConfigError for `path` with `reason`, naming the file (or "--set"):
  // for checks across fields that a service makes itself.
  [[noreturn]] void fail(std::string_view path, const std::string& reason) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

#define HYSTLOOP_CONFIG_EXTERN(T)                                     \
  extern template T Config::get<T>(std::string_view, const T&) const; \
  extern template T Config::get<T>(std::string_view) const;
HYSTLOOP_CONFIG_EXTERN(bool)
HYSTLOOP_CONFIG_EXTERN(int)
HYSTLOOP_CONFIG_EXTERN(std::int64_t)
HYSTLOOP_CONFIG_EXTERN(double)
HYSTLOOP_CONFIG_EXTERN(std::string)
HYSTLOOP_CONFIG_EXTERN(std::vector<double>)
HYSTLOOP_CONFIG_EXTERN(std::vector<std::string>)
#undef HYSTLOOP_CONFIG_EXTERN

}  // namespace hystloop
