// libFuzzer target: any text as a service configuration. The YAML loader, a --set override and the
// typed, range-checked getters every service reads its keys with (common/core/config.hpp) either
// accept the text or refuse it with an exception naming the field; they never crash, hang or read
// out of bounds.
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string>

#include "core/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hystloop;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    Config config = Config::from_string(text, "fuzz.yaml");
    for (const std::string& key : config.keys()) {
      try {
        (void)config.get_in_range(key, 0.0, -1e6, 1e6);
      } catch (const std::exception&) {
      }
      try {
        (void)config.get_int_in_range(key, 0, -1000, 1000);
      } catch (const std::exception&) {
      }
      try {
        (void)config.get<std::string>(key);
      } catch (const std::exception&) {
      }
      try {
        (void)config.get<bool>(key);
      } catch (const std::exception&) {
      }
    }
    try {
      config.check_no_unknown_keys({"bridge.rate_hz", "actuator.*", "servo.kp"});
    } catch (const std::exception&) {
    }
    config.apply_override(text.substr(0, text.find('\n')));  // the first line as a --set
    (void)config.dump();
  } catch (const std::exception&) {  // a refusal is a correct answer to bad input
  }
  return 0;
}
