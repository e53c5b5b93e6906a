#include "runtime/summary_file.hpp"

#include <fstream>
#include <stdexcept>
#include <system_error>

namespace hystloop {

std::string to_json_text(const nlohmann::ordered_json& value) {
  return value.dump(2, ' ', true, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

void write_file_atomically(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path tmp = path.string() + ".tmp";
  std::error_code ec;
  const auto fail = [&](const std::string& what) {
    std::filesystem::remove(tmp, ec);  // no stray temporary file left behind
    throw std::runtime_error(what);
  };
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) fail("cannot write " + tmp.string());
    out << text;
    out.flush();
    if (!out) fail("cannot write " + tmp.string() + " (disk full?)");
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) fail("cannot rename " + tmp.string() + " to " + path.string() + ": " + ec.message());
}

}  // namespace hystloop
