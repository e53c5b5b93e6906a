// LogLimiter: at most one line per reason per interval, the next one says how many were
// suppressed; escape_wire: text off the wire never puts control bytes into a log line.
#include "core/log_limiter.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

namespace hystloop {
namespace {

constexpr std::int64_t kSecond = 1'000'000'000;

TEST(LogLimiter, OneLinePerReasonPerIntervalThenSaysHowManyWereSuppressed) {
  LogLimiter limiter(kSecond);
  const LogLimiter::Gate first = limiter.allow(0, 5 * kSecond);
  EXPECT_TRUE(first);
  EXPECT_EQ(first.suppressed, 0u);
  EXPECT_EQ(suppressed_note(first), "");
  for (int i = 1; i <= 999; ++i) EXPECT_FALSE(limiter.allow(0, 5 * kSecond + std::int64_t{i} * 1'000'000)) << i;
  EXPECT_TRUE(limiter.allow(1, 5 * kSecond + 500'000'000));  // another reason has its own budget
  const LogLimiter::Gate resumed = limiter.allow(0, 6 * kSecond);
  ASSERT_TRUE(resumed);
  EXPECT_EQ(resumed.suppressed, 999u);
  EXPECT_EQ(suppressed_note(resumed), "; 999 more suppressed");
  EXPECT_EQ(limiter.suppressed_total(), 999u);
  const LogLimiter::Gate quiet = limiter.allow(0, 60 * kSecond);  // nothing suppressed since
  EXPECT_TRUE(quiet);
  EXPECT_EQ(quiet.suppressed, 0u);
}

TEST(LogLimiter, AClockThatWentBackAndReasonsOutOfRangeAreSafe) {
  LogLimiter limiter(kSecond);
  EXPECT_TRUE(limiter.allow(3, 10 * kSecond));
  EXPECT_TRUE(limiter.allow(3, 2 * kSecond));  // went back: let through rather than silent
  EXPECT_TRUE(limiter.allow(1000, 0));         // shares the last slot
  EXPECT_FALSE(limiter.allow(LogLimiter::kMaxReasons - 1, 1));
}

TEST(EscapeWire, PrintableStaysEverythingElseBecomesHex) {
  EXPECT_EQ(escape_wire("reident@lab-1 v2"), "reident@lab-1 v2");
  EXPECT_EQ(escape_wire(std::string("a\x1b[2Jb\n\r\t", 9)), "a\\x1b[2Jb\\x0a\\x0d\\x09");
  EXPECT_EQ(escape_wire(std::string("x\0y", 3)), "x\\x00y");
  EXPECT_EQ(escape_wire("\xff\x80\x7f"), "\\xff\\x80\\x7f");
  EXPECT_EQ(escape_wire("back\\slash"), "back\\\\slash");  // an escape in the input cannot pass for ours
  EXPECT_EQ(escape_wire(std::string(500, 'a'), 10), std::string(10, 'a') + "...");
  EXPECT_EQ(escape_wire(""), "");
}

}  // namespace
}  // namespace hystloop
