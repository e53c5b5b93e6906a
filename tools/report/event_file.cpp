#include "event_file.hpp"

#include <sys/types.h>

#include <stdexcept>

namespace hystloop::report {
namespace {

constexpr std::uint32_t kSync = 0xEDA1DA01u;
constexpr std::uint64_t kHeaderBytes = 28;      // sync, event number, timestamp, two lengths
constexpr std::int32_t kMaxChannelBytes = 999;  // as liblcm's reader

std::uint64_t be(const std::uint8_t* p, int n) {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

}  // namespace

EventFileReader::EventFileReader(const std::filesystem::path& file) {
  if (!std::filesystem::is_regular_file(file)) throw std::runtime_error(file.string() + ": no such log file");
  file_ = std::fopen(file.c_str(), "rb");
  if (file_ == nullptr) throw std::runtime_error(file.string() + ": cannot open as an LCM event log");
  scan_.file = file.string();
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  scan_.bytes = ec ? 0 : static_cast<std::uint64_t>(size);
}

EventFileReader::~EventFileReader() {
  if (file_ != nullptr) std::fclose(file_);
}

bool EventFileReader::read_exact(void* out, std::size_t n) { return n == 0 || std::fread(out, 1, n, file_) == n; }

const lcm::LogEvent* EventFileReader::next() {
  while (true) {
    // Find the next sync word.
    std::uint32_t window = 0;
    std::uint64_t consumed = 0;
    int c = 0;
    while ((c = std::fgetc(file_)) != EOF) {
      window = (window << 8) | static_cast<std::uint32_t>(c);
      if (++consumed >= 4 && window == kSync) break;
    }
    if (c == EOF) {
      scan_.trailing_bytes = scan_.bytes > end_of_last_ ? scan_.bytes - end_of_last_ : 0;
      return nullptr;
    }
    const off_t here = ::ftello(file_);
    const std::uint64_t start = static_cast<std::uint64_t>(here) - 4;
    std::uint8_t header[kHeaderBytes - 4];
    const bool whole_header = read_exact(header, sizeof header);
    const auto channel_len = static_cast<std::int32_t>(be(header + 16, 4));
    const auto data_len = static_cast<std::int32_t>(be(header + 20, 4));
    const std::uint64_t end = start + kHeaderBytes + static_cast<std::uint64_t>(channel_len > 0 ? channel_len : 0) +
                              static_cast<std::uint64_t>(data_len > 0 ? data_len : 0);
    const bool fits =
        whole_header && channel_len > 0 && channel_len <= kMaxChannelBytes && data_len >= 0 && end <= scan_.bytes;
    if (fits) {
      channel_.resize(static_cast<std::size_t>(channel_len));
      data_.resize(static_cast<std::size_t>(data_len));
      if (read_exact(channel_.data(), channel_.size()) && read_exact(data_.data(), data_.size())) {
        scan_.skipped_bytes += start - end_of_last_;
        end_of_last_ = end;
        ++scan_.events;
        event_.eventnum = static_cast<std::int64_t>(be(header, 8));
        event_.timestamp = static_cast<std::int64_t>(be(header + 8, 8));
        event_.channel = channel_;
        event_.datalen = data_len;
        event_.data = data_.data();
        return &event_;
      }
    }
    // Not an event: look again from the byte after this sync word.
    ::fseeko(file_, static_cast<off_t>(start + 1), SEEK_SET);
  }
}

}  // namespace hystloop::report
