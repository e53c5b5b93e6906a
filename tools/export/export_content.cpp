#include "export_content.hpp"

namespace hystloop::exporter {

std::string identifier(const std::string& text, std::size_t max_length) {
  std::string out;
  for (const char c : text) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
    out += ok ? c : '_';
  }
  if (out.empty() || !((out[0] >= 'A' && out[0] <= 'Z') || (out[0] >= 'a' && out[0] <= 'z'))) out = "x" + out;
  if (out.size() > max_length) out.resize(max_length);
  return out;
}

}  // namespace hystloop::exporter
