// The rig client's side without a rig: every acknowledged request ends within its timeout with a
// RigError in hystloop-ctl's words, a recording with no sensor stream says so, and requests the
// contract or the servo's bounds refuse are refused by name before anything is sent.
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "core/errors.hpp"
#include "rig_client.hpp"

namespace hystloop::ctl {
namespace {

RigClientOptions in_process() {
  RigClientOptions o;
  o.link.lcm_url = "memq://";  // nothing leaves the process
  o.timeout_s = 0.3;
  return o;
}

template <class F>
std::string rig_error(F&& f) {
  try {
    f();
  } catch (const RigError& e) {
    return e.what();
  }
  return "no RigError";
}

TEST(RigClient, WithoutARigEveryRequestEndsInItsTimeoutSayingSo) {
  RigClient rig(in_process());
  const auto start = std::chrono::steady_clock::now();
  EXPECT_NE(rig_error([&] { rig.arm(); }).find("no rig is running"), std::string::npos);
  const double waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(waited_s, 2.0) << "a request without a rig must end within its timeout (0.3 s)";
  EXPECT_NE(rig_error([&] { rig.learn("on"); }).find("not confirmed"), std::string::npos);
  TrajectoryRequest t;
  t.shape = "cosine";
  t.amplitude_m = 1e-6;
  EXPECT_NE(rig_error([&] { rig.set_trajectory(t); }).find("no status from 'compensator'"), std::string::npos);
  EXPECT_NE(rig_error([&] { rig.record(0.2); }).find("no sensor blocks"), std::string::npos);
  EXPECT_FALSE(rig.next_block(0.1).has_value());
  EXPECT_TRUE(rig.status(0.1).empty());
}

TEST(RigClient, RefusesBadRequestsByNameBeforeSending) {
  RigClient rig(in_process());
  try {
    rig.set_gains(GainsRequest{});
    FAIL() << "an empty gains request taken";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "gains");
  }
  GainsRequest g;
  g.kp = 5.0;  // beyond the servo's bound of 2
  EXPECT_THROW(rig.set_gains(g), ParameterError);
  EXPECT_THROW(rig.set_mode("sideways"), ParameterError);
  EXPECT_THROW(rig.learn("maybe"), ParameterError);
  ExperimentRequest e;
  e.amplitude_V = 10.0;
  e.frequency_Hz = 1.0;
  e.duration_s = 1.0;
  EXPECT_THROW(rig.experiment(e, 3), ParameterError);
  ParamsRequest p;
  p.c1 = -1.0;
  EXPECT_THROW(rig.set_params(p), ParameterError);
  EXPECT_THROW(rig.record(0.0), ParameterError);
  RigClientOptions bad = in_process();
  bad.timeout_s = 0.0;
  EXPECT_THROW(RigClient{bad}, ParameterError);
}

}  // namespace
}  // namespace hystloop::ctl
