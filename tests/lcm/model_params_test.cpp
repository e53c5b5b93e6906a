// model_params_t (HX_MODEL), the parameter message of any model: the length walk agrees with the
// encoding and refuses a corrupted operator count before decoding; every field's contract; an
// unknown kind or format passes the envelope (so a receiver can count it by its own reason) but
// never check_message; a Subscription counts every refusal.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "lcm/message_checks.hpp"
#include "lcm/message_fixtures.hpp"
#include "lcm/subscription.hpp"
#include "lcm/wire_layout.hpp"
#include "model_params_fixtures.hpp"
#include "models/model_set.hpp"

namespace hystloop {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(ModelParamsMessage, WalkCoversExactlyTheEncodedBytesOfEveryKind) {
  for (std::int64_t k = 0; k < 40; ++k) {  // every kind, 1..32 operators
    const auto m = fixtures::model_params(k);
    EXPECT_EQ(check_message(m), Verdict::kOk) << k;
    const auto bytes = fixtures::encode(m);
    EXPECT_EQ(walk_wire_layout(wire_layout_of<model_params_t>(), bytes.data(), bytes.size()),
              static_cast<std::int64_t>(bytes.size()))
        << k;
  }
}

// The operator count sits after format(1) utime(8) version(4) publisher(8) kind(1) mem(24) linear(16).
constexpr std::size_t kCountOffset = 8 + 1 + 8 + 4 + 8 + 1 + 24 + 16;

TEST(ModelParamsMessage, ACorruptedOperatorCountIsRefusedBeforeDecoding) {
  auto bytes = fixtures::encode(fixtures::model_params(1));  // PI, 2 operators
  for (const std::int32_t count : {-1, 33, 1 << 30, 3}) {
    std::vector<std::uint8_t> b(bytes.begin(), bytes.end());
    const auto u = static_cast<std::uint32_t>(count);
    for (std::size_t i = 0; i < 4; ++i) b.at(kCountOffset + i) = static_cast<std::uint8_t>(u >> (24 - 8 * i));
    EXPECT_EQ(walk_wire_layout(wire_layout_of<model_params_t>(), b.data(), b.size()), -1) << count;
  }
  for (std::size_t cut = 0; cut < bytes.size(); cut += 7) {
    EXPECT_EQ(walk_wire_layout(wire_layout_of<model_params_t>(), bytes.data(), cut), -1) << cut;
  }
}

TEST(ModelParamsMessage, EveryNumberMustBeFinite) {
  using M = model_params_t;
  for (double M::*field : {&M::mem_c1,
                           &M::mem_c2,
                           &M::mem_c3,
                           &M::linear_gain,
                           &M::linear_offset_m,
                           &M::kat_k1,
                           &M::kat_k2,
                           &M::kat_k2_slope,
                           &M::kat_k2_domain_min,
                           &M::kat_k2_domain_max,
                           &M::kat_initial_offset,
                           &M::kat_in_gain,
                           &M::kat_in_offset,
                           &M::kat_in_domain_min,
                           &M::kat_in_domain_max,
                           &M::kat_in_amplitude,
                           &M::kat_in_scale,
                           &M::kat_out_gain,
                           &M::kat_out_offset,
                           &M::kat_out_domain_min,
                           &M::kat_out_domain_max,
                           &M::kat_out_amplitude,
                           &M::kat_out_scale,
                           &M::residual_m,
                           &M::window_s}) {
    for (std::int64_t k = 0; k < 4; ++k) {  // in the fields of its own kind and of the others
      for (const double bad : {kNaN, kInf}) {
        auto m = fixtures::model_params(k);
        m.*field = bad;
        EXPECT_EQ(check_message(m), Verdict::kNonFinite) << k;
        EXPECT_EQ(check_model_params_envelope(m), Verdict::kNonFinite) << k;
      }
    }
  }
  for (std::size_t i = 0; i < 8; ++i) {
    auto m = fixtures::model_params(2);
    m.kat_out_coefficients[i] = kNaN;
    EXPECT_EQ(check_message(m), Verdict::kNonFinite) << i;
    m = fixtures::model_params(2);
    m.kat_in_coefficients[i] = -kInf;
    EXPECT_EQ(check_message(m), Verdict::kNonFinite) << i;
  }
  auto m = fixtures::model_params(5);  // PI, 2 operators
  m.pi_weights[1] = kNaN;
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
  m = fixtures::model_params(5);
  m.pi_thresholds_V[1] = kInf;
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
  m = fixtures::model_params(1);
  m.heldout_rms_m = kNaN;  // not ranked: documented
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.heldout_rms_m = kInf;
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
}

TEST(ModelParamsMessage, EnvelopeRanges) {
  const auto refused = [](const model_params_t& m) { return check_message(m) == Verdict::kOutOfRange; };
  auto m = fixtures::model_params(3);
  m.version = 0;
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(3);
  m.utime = -1;
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(3);
  m.samples_used = -1;
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(3);
  m.residual_m = -1e-9;
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(3);
  m.heldout_rms_m = -1e-9;
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(3);
  m.window_s = -1.0;
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(3);
  m.source = std::string("a\0b", 3);
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(3);
  m.publisher_id = std::numeric_limits<std::int64_t>::min();  // any id names a publisher
  m.valid = false;                                            // the consumer's decision
  EXPECT_EQ(check_message(m), Verdict::kOk);
}

TEST(ModelParamsMessage, ArraysMustHoldTheirCount) {
  auto m = fixtures::model_params(5);
  m.pi_weights.pop_back();
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::model_params(5);
  m.n_operators = model_params_t::MAX_OPERATORS + 1;
  m.pi_thresholds_V.resize(33, 1.0);
  m.pi_weights.resize(33, 1.0);
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::model_params(4);  // MEM: no operators is right
  EXPECT_EQ(m.n_operators, 0);
  EXPECT_EQ(check_message(m), Verdict::kOk);
}

TEST(ModelParamsMessage, KindSpecificRanges) {
  const auto refused = [](const model_params_t& m) { return check_message(m) == Verdict::kOutOfRange; };
  auto m = fixtures::model_params(0);
  m.mem_c1 = 0.0;
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(0);
  m.mem_c2 = -1e-15;
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(0);
  m.mem_c3 = 51.0;
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(1);
  m.n_operators = 0;
  m.pi_thresholds_V.clear();
  m.pi_weights.clear();
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(5);
  m.pi_thresholds_V[0] = 1.0;  // r_0 = 0
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(5);
  m.pi_thresholds_V[1] = 0.0;  // strictly increasing
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(5);
  m.pi_weights[0] = 0.0;
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(3);
  m.linear_gain = 0.0;
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(2);
  m.kat_k1 = 0.0;
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(2);
  m.kat_out_shaping = 3;
  EXPECT_TRUE(refused(m));
  m = fixtures::model_params(0);
  m.linear_gain = 0.0;  // another kind's field: not this set's
  EXPECT_EQ(check_message(m), Verdict::kOk);
}

TEST(ModelParamsMessage, AnUnknownKindOrFormatPassesTheEnvelopeOnly) {
  for (const std::int8_t kind : {std::int8_t{kModelKindCount}, std::int8_t{-1}, std::int8_t{127}}) {
    auto m = fixtures::model_params(0);
    m.kind = kind;
    EXPECT_EQ(check_model_params_envelope(m), Verdict::kOk) << int{kind};
    EXPECT_EQ(check_message(m), Verdict::kOutOfRange) << int{kind};
  }
  auto m = fixtures::model_params(0);
  m.format_version = model_params_t::FORMAT_VERSION + 1;  // a later format
  EXPECT_EQ(check_model_params_envelope(m), Verdict::kOk);
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
}

TEST(ModelParamsMessage, ASubscriptionCountsEveryRefusal) {
  lcm::LCM lcm{"memq://"};
  Subscription<model_params_t> sub(lcm, "HX_MODEL");
  auto good = fixtures::encode(fixtures::model_params(1));
  sub.receive(good.data(), good.size(), 0);
  auto bad = fixtures::model_params(1);
  bad.kind = 9;
  auto bytes = fixtures::encode(bad);
  sub.receive(bytes.data(), bytes.size(), 0);
  bad = fixtures::model_params(1);
  bad.pi_weights[0] = kNaN;
  bytes = fixtures::encode(bad);
  sub.receive(bytes.data(), bytes.size(), 0);
  good[kCountOffset] = 0x7f;  // a count of ~2^31
  sub.receive(good.data(), good.size(), 0);
  const EndpointCounters& c = sub.counters();
  EXPECT_EQ(c.received, 4u);
  EXPECT_EQ(c.accepted, 1u);
  EXPECT_EQ(c.rejected(RejectReason::kOutOfRange), 1u);
  EXPECT_EQ(c.rejected(RejectReason::kNonFinite), 1u);
  EXPECT_EQ(c.rejected(RejectReason::kDecodeFailed), 1u);
  EXPECT_EQ(sub.latest().n_operators, 2);
}

}  // namespace
}  // namespace hystloop
