// The authentication trailer (auth/message_auth.hpp): what is signed verifies once, and any
// change to the body, the trailer or the channel, another key, a counter that does not go up,
// a counter too far from the receiver's clock and a missing or short trailer are refused.
#include "auth/message_auth.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

constexpr std::int64_t kNow = 1'800'000'000'000'000;  // us since the epoch
constexpr std::int64_t kSkew = 2'000'000;

RigKey key_of(unsigned char seed) {
  RigKey k;
  for (std::size_t i = 0; i < k.bytes.size(); ++i) k.bytes[i] = static_cast<unsigned char>(seed + 7 * i);
  return k;
}

struct Signed {
  std::vector<unsigned char> bytes;  // body then trailer
  std::size_t body = 0;
};

Signed sign(MessageSigner& signer, const std::string& channel, std::vector<unsigned char> body, std::int64_t now) {
  Signed s;
  s.body = body.size();
  s.bytes = std::move(body);
  s.bytes.resize(s.body + kAuthTrailerBytes);
  signer.sign(channel, s.bytes.data(), s.body, now, s.bytes.data() + s.body);
  return s;
}

AuthResult check(MessageVerifier& v, const std::string& channel, const Signed& s, std::int64_t now = kNow) {
  return v.verify(channel, s.bytes.data(), s.body, s.bytes.data() + s.body, s.bytes.size() - s.body, now);
}

std::vector<unsigned char> body(std::size_t n) {
  std::vector<unsigned char> b(n);
  for (std::size_t i = 0; i < n; ++i) b[i] = static_cast<unsigned char>(i * 31 + 5);
  return b;
}

TEST(MessageAuth, RoundTripVerifiesAndTheTrailerIsLaidOutAsDocumented) {
  MessageSigner signer(key_of(1), 0x0102030405060708ull);
  MessageVerifier verifier(key_of(1), kSkew);
  const Signed s = sign(signer, "HX_COMMAND", body(100), kNow);
  ASSERT_EQ(s.bytes.size(), 100u + 52u);
  EXPECT_EQ(std::string(s.bytes.begin() + 100, s.bytes.begin() + 104), "HXA1");
  EXPECT_EQ(s.bytes[104], 0x01);
  EXPECT_EQ(s.bytes[111], 0x08);
  EXPECT_EQ(signer.last_counter(), kNow);
  EXPECT_EQ(check(verifier, "HX_COMMAND", s), AuthResult::kOk);
}

TEST(MessageAuth, EveryTamperedByteOfBodyOrTrailerIsRefused) {
  MessageSigner signer(key_of(1));
  const Signed s = sign(signer, "HX_CONTROL", body(40), kNow);
  for (std::size_t i = 0; i < s.bytes.size(); ++i) {
    MessageVerifier verifier(key_of(1), kSkew);
    Signed t = s;
    t.bytes[i] ^= 0x01;
    const AuthResult r = check(verifier, "HX_CONTROL", t);
    if (i >= 40 && i < 44) {
      EXPECT_EQ(r, AuthResult::kMalformed) << "magic byte " << i;
    } else {
      EXPECT_EQ(r, AuthResult::kBadMac) << "byte " << i;
    }
  }
}

TEST(MessageAuth, AnotherChannelOrKeyIsRefused) {
  MessageSigner signer(key_of(1));
  const Signed s = sign(signer, "HX_PARAMS", body(60), kNow);
  MessageVerifier same(key_of(1), kSkew);
  EXPECT_EQ(check(same, "HX_COMMAND", s), AuthResult::kBadMac);
  EXPECT_EQ(check(same, "RIG2_PARAMS", s), AuthResult::kBadMac);
  MessageVerifier other(key_of(2), kSkew);
  EXPECT_EQ(check(other, "HX_PARAMS", s), AuthResult::kBadMac);
  EXPECT_EQ(check(same, "HX_PARAMS", s), AuthResult::kOk);
}

TEST(MessageAuth, EqualOrEarlierCounterFromTheSameSenderIsReplayed) {
  MessageSigner signer(key_of(1));
  MessageVerifier verifier(key_of(1), kSkew);
  const Signed first = sign(signer, "HX_COMMAND", body(30), kNow);
  const Signed second = sign(signer, "HX_COMMAND", body(30), kNow + 10);
  EXPECT_EQ(check(verifier, "HX_COMMAND", first), AuthResult::kOk);
  EXPECT_EQ(check(verifier, "HX_COMMAND", first), AuthResult::kReplayed);  // equal counter
  EXPECT_EQ(check(verifier, "HX_COMMAND", second), AuthResult::kOk);
  EXPECT_EQ(check(verifier, "HX_COMMAND", first), AuthResult::kReplayed);  // backwards
  EXPECT_EQ(check(verifier, "HX_COMMAND", second), AuthResult::kReplayed);
}

TEST(MessageAuth, CounterStrictlyIncreasesWhenTheClockStandsStillOrStepsBack) {
  MessageSigner signer(key_of(1));
  MessageVerifier verifier(key_of(1), kSkew);
  for (int i = 0; i < 5; ++i) {
    const Signed s = sign(signer, "HX_COMMAND", body(8), kNow - i);  // clock stepped back
    EXPECT_EQ(signer.last_counter(), kNow + i);
    EXPECT_EQ(check(verifier, "HX_COMMAND", s), AuthResult::kOk) << i;
  }
}

TEST(MessageAuth, CounterTooOldOrInTheFutureIsSkewed) {
  MessageSigner signer(key_of(1));
  const Signed s = sign(signer, "HX_COMMAND", body(8), kNow);
  MessageVerifier v1(key_of(1), kSkew);
  EXPECT_EQ(check(v1, "HX_COMMAND", s, kNow + kSkew + 1), AuthResult::kSkewed);  // a recording
  EXPECT_EQ(check(v1, "HX_COMMAND", s, kNow - kSkew - 1), AuthResult::kSkewed);  // from the future
  EXPECT_EQ(check(v1, "HX_COMMAND", s, kNow + kSkew), AuthResult::kOk);          // edge: accepted
}

TEST(MessageAuth, MissingOrShortTrailerIsUnsignedOrMalformed) {
  MessageSigner signer(key_of(1));
  MessageVerifier verifier(key_of(1), kSkew);
  const Signed s = sign(signer, "HX_COMMAND", body(20), kNow);
  EXPECT_EQ(verifier.verify("HX_COMMAND", s.bytes.data(), 20, nullptr, 0, kNow), AuthResult::kUnsigned);
  for (std::size_t n = 1; n < kAuthTrailerBytes; ++n) {
    EXPECT_EQ(verifier.verify("HX_COMMAND", s.bytes.data(), 20, s.bytes.data() + 20, n, kNow), AuthResult::kMalformed)
        << n;
  }
  std::vector<unsigned char> longer = s.bytes;
  longer.push_back(0);
  EXPECT_EQ(verifier.verify("HX_COMMAND", longer.data(), 20, longer.data() + 20, kAuthTrailerBytes + 1, kNow),
            AuthResult::kMalformed);
  EXPECT_EQ(check(verifier, "HX_COMMAND", s), AuthResult::kOk);  // none of that used the counter
}

TEST(MessageAuth, SendersAreTrackedApartAndAFullTableForgetsTheOldest) {
  MessageVerifier verifier(key_of(1), kSkew);
  std::vector<Signed> firsts;
  for (std::uint64_t id = 1; id <= MessageVerifier::kMaxSenders + 1; ++id) {
    MessageSigner signer(key_of(1), id);
    firsts.push_back(sign(signer, "HX_CONTROL", body(8), kNow + static_cast<std::int64_t>(id)));
    EXPECT_EQ(check(verifier, "HX_CONTROL", firsts.back()), AuthResult::kOk) << id;
  }
  EXPECT_EQ(verifier.evictions(), 1u);
  // Sender 1 was forgotten (its replay within the skew window is accepted once), the others not.
  EXPECT_EQ(check(verifier, "HX_CONTROL", firsts[1]), AuthResult::kReplayed);
  EXPECT_EQ(check(verifier, "HX_CONTROL", firsts.back()), AuthResult::kReplayed);
}

TEST(MessageAuth, SignAndVerifyAllocateNothing) {
  MessageSigner signer(key_of(1));
  MessageVerifier verifier(key_of(1), kSkew);
  std::vector<unsigned char> buffer = body(400);
  buffer.resize(400 + kAuthTrailerBytes);
  testing::AllocationCounter counter;
  for (int i = 0; i < 100; ++i) {
    signer.sign("HX_COMMAND", buffer.data(), 400, kNow + i, buffer.data() + 400);
    EXPECT_EQ(verifier.verify("HX_COMMAND", buffer.data(), 400, buffer.data() + 400, kAuthTrailerBytes, kNow + i),
              AuthResult::kOk);
  }
  EXPECT_EQ(counter.allocations(), 0u);
}

TEST(MessageAuth, SenderIdsAreRandomAndNonZero) {
  MessageSigner a(key_of(1));
  MessageSigner b(key_of(1));
  EXPECT_NE(a.sender_id(), 0u);
  EXPECT_NE(a.sender_id(), b.sender_id());
}

// A receiver that has just started has seen no sender: without not_before an ARM captured a
// second before it started (before the operator's DISARM) would re-arm it once.
TEST(MessageAuth, AReceiverRefusesWhatWasSignedBeforeItStarted) {
  MessageSigner signer(key_of(1));
  const Signed before = sign(signer, "HX_CONTROL", body(40), kNow - 1'000'000);  // 1 s before the start
  const Signed after = sign(signer, "HX_CONTROL", body(40), kNow + 10);
  MessageVerifier restarted(key_of(1), kSkew, kNow);
  EXPECT_EQ(check(restarted, "HX_CONTROL", before, kNow + 20), AuthResult::kReplayed);
  EXPECT_EQ(check(restarted, "HX_CONTROL", after, kNow + 20), AuthResult::kOk);
  // Without the bound (0) the captured message would pass: the check above is what refuses it.
  MessageVerifier unbounded(key_of(1), kSkew);
  EXPECT_EQ(check(unbounded, "HX_CONTROL", before, kNow + 20), AuthResult::kOk);
}

}  // namespace
}  // namespace hystloop
