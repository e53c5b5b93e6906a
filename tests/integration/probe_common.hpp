#pragma once
// What the integration probes (lcm_probe, logger_probe, reident_stream) share: a command line of a
// mode and `--key value` options, the dispatch to a mode's function, a main() that turns a refused
// command line into exit status 2, and the SHUTDOWN request a probe sends to one service.

#include <cstdint>
#include <cstdio>
#include <exception>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "hystloop/control_t.hpp"
#include "lcm/publisher.hpp"

namespace hystloop::probe {

// Where an option's value goes: the text as given, an integer, a number, or a flag (true for "1").
using OptionTarget = std::variant<std::string*, std::int64_t*, double*, bool*>;
struct OptionSpec {
  const char* key;
  OptionTarget into;
};

// argv[1], the mode; throws std::invalid_argument(usage) when there is none.
inline std::string mode_of(int argc, char** argv, const char* usage) {
  if (argc < 2) throw std::invalid_argument(usage);
  return argv[1];
}

// Reads argv[2..] as `--key value` pairs into the targets of `specs`. An unknown key, or a key
// without a value, throws std::invalid_argument; so does an argument that does not start with "--"
// unless `operands` is given, which then collects them in order.
inline void parse_options(int argc, char** argv, std::initializer_list<OptionSpec> specs,
                          std::vector<std::string>* operands = nullptr) {
  for (int i = 2; i < argc; ++i) {
    const std::string key = argv[i];
    if (operands != nullptr && key.rfind("--", 0) != 0) {
      operands->push_back(key);
      continue;
    }
    const OptionSpec* spec = nullptr;
    for (const OptionSpec& s : specs) {
      if (key == s.key) spec = &s;
    }
    if (spec == nullptr) throw std::invalid_argument("unknown option " + key);
    if (i + 1 >= argc) throw std::invalid_argument(key + " needs a value");
    const std::string value = argv[++i];
    std::visit(
        [&](auto* into) {
          using T = std::remove_pointer_t<decltype(into)>;
          if constexpr (std::is_same_v<T, std::string>)
            *into = value;
          else if constexpr (std::is_same_v<T, std::int64_t>)
            *into = std::stoll(value);
          else if constexpr (std::is_same_v<T, double>)
            *into = std::stod(value);
          else
            *into = value == "1";
        },
        spec->into);
  }
}

// Runs the function of options.mode; an unknown mode prints "<name>: unknown mode M" and gives 2.
template <class Options>
int run_mode(const char* name, const Options& options,
             std::initializer_list<std::pair<const char*, int (*)(const std::type_identity_t<Options>&)>> modes) {
  for (const auto& [mode, run] : modes) {
    if (options.mode == mode) return run(options);
  }
  std::fprintf(stderr, "%s: unknown mode %s\n", name, options.mode.c_str());
  return 2;
}

// A probe's main(): body's exit status; what it throws is printed as "<name>: <what>" and gives 2
// for a refused command line (std::invalid_argument) and `failure_status` for anything else.
template <class Body>
int run_probe(const char* name, Body&& body, int failure_status = 2) {
  try {
    return body();
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    return failure_status;
  }
}

// control_t SHUTDOWN addressed to one process, sent three times as senders do over UDP (the
// process acts once per request id). True when every publish succeeded.
inline bool send_shutdown(lcm::LCM& lcm, const std::string& channel, const std::string& target, std::int64_t utime) {
  control_t msg{};
  msg.utime = utime;
  msg.request_id = 4242;
  msg.command = control_t::SHUTDOWN;
  msg.target = target;
  Publisher<control_t> publisher(lcm, channel);
  bool ok = true;
  for (int i = 0; i < 3; ++i) ok = publisher.publish(msg) && ok;
  return ok;
}

}  // namespace hystloop::probe
