#include "follow_bot_common/velocity_limiter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "follow_bot_common/testing/garbage_numbers.h"

namespace follow_bot_common {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.141592653589793;

TEST(VelocityLimiter, DefaultsAreValid) {
  EXPECT_EQ(validate(VelocityLimiterConfig()), "");
  const VelocityLimiterConfig config;
  EXPECT_DOUBLE_EQ(config.max_linear, 0.7);
  EXPECT_DOUBLE_EQ(config.max_angular, kPi);
  EXPECT_FALSE(config.allow_reverse);
}

TEST(VelocityLimiter, RejectsNonPositiveAndNonFiniteLimits) {
  double VelocityLimiterConfig::*fields[] = {
      &VelocityLimiterConfig::max_linear, &VelocityLimiterConfig::max_angular,
      &VelocityLimiterConfig::max_linear_accel, &VelocityLimiterConfig::max_angular_accel};
  const char* names[] = {"max_linear", "max_angular", "max_linear_accel", "max_angular_accel"};
  for (int i = 0; i < 4; ++i) {
    for (double bad : {0.0, -1.0, kNaN, kInf}) {
      VelocityLimiterConfig config;
      config.*fields[i] = bad;
      const std::string error = validate(config);
      EXPECT_NE(error.find(names[i]), std::string::npos) << error;
      EXPECT_THROW(VelocityLimiter{config}, std::invalid_argument);
    }
  }
}

TEST(VelocityLimiter, ClampsMagnitudes) {
  VelocityLimiter limiter;
  // A long dt so that only the magnitude bounds act.
  Twist2D out = limiter.limit({5.0, -10.0}, 100.0);
  EXPECT_DOUBLE_EQ(out.linear, 0.7);
  EXPECT_DOUBLE_EQ(out.angular, -kPi);
  out = limiter.limit({0.3, 10.0}, 100.0);
  EXPECT_DOUBLE_EQ(out.linear, 0.3);
  EXPECT_DOUBLE_EQ(out.angular, kPi);
}

TEST(VelocityLimiter, ClampsReverseUnlessAllowed) {
  VelocityLimiter forward_only;
  EXPECT_DOUBLE_EQ(forward_only.limit({-0.5, 0.0}, 100.0).linear, 0.0);

  VelocityLimiterConfig config;
  config.allow_reverse = true;
  VelocityLimiter reversing(config);
  EXPECT_DOUBLE_EQ(reversing.limit({-0.5, 0.0}, 100.0).linear, -0.5);
  EXPECT_DOUBLE_EQ(reversing.limit({-5.0, 0.0}, 100.0).linear, -0.7);
}

TEST(VelocityLimiter, RateLimitsBothWays) {
  VelocityLimiter limiter;  // 1 m/s^2, 6 rad/s^2
  Twist2D out = limiter.limit({0.7, 3.0}, 0.1);
  EXPECT_NEAR(out.linear, 0.1, 1e-12);
  EXPECT_NEAR(out.angular, 0.6, 1e-12);
  out = limiter.limit({0.7, 3.0}, 0.1);
  EXPECT_NEAR(out.linear, 0.2, 1e-12);
  EXPECT_NEAR(out.angular, 1.2, 1e-12);
  // Deceleration is bounded too (only stop() bypasses it).
  out = limiter.limit({0.0, -3.0}, 0.05);
  EXPECT_NEAR(out.linear, 0.15, 1e-12);
  EXPECT_NEAR(out.angular, 0.9, 1e-12);
}

TEST(VelocityLimiter, FirstCommandRampsFromRest) {
  VelocityLimiter limiter;
  EXPECT_NEAR(limiter.limit({0.5, 0.0}, 0.02).linear, 0.02, 1e-12);
}

TEST(VelocityLimiter, WithoutUsableDtOnlySlowsDown) {
  for (double bad_dt : {0.0, -0.1, kNaN, kInf, -kInf}) {
    VelocityLimiter limiter;
    // From rest nothing may start moving.
    Twist2D out = limiter.limit({0.5, 1.0}, bad_dt);
    EXPECT_EQ(out.linear, 0.0) << bad_dt;
    EXPECT_EQ(out.angular, 0.0) << bad_dt;

    limiter.limit({0.5, 1.0}, 10.0);  // now moving at {0.5, 1.0}
    out = limiter.limit({0.6, 2.0}, bad_dt);
    EXPECT_DOUBLE_EQ(out.linear, 0.5) << "no speeding up, dt " << bad_dt;
    EXPECT_DOUBLE_EQ(out.angular, 1.0);
    out = limiter.limit({0.2, 0.4}, bad_dt);
    EXPECT_DOUBLE_EQ(out.linear, 0.2) << "slowing down is allowed, dt " << bad_dt;
    EXPECT_DOUBLE_EQ(out.angular, 0.4);
    out = limiter.limit({0.2, -1.0}, bad_dt);
    EXPECT_DOUBLE_EQ(out.angular, 0.0) << "a reversal stops at zero, dt " << bad_dt;
  }
}

TEST(VelocityLimiter, ReplacesNonFiniteComponentsByZero) {
  VelocityLimiter limiter;
  limiter.limit({0.5, 1.0}, 10.0);
  Twist2D out = limiter.limit({kNaN, kInf}, 10.0);
  EXPECT_EQ(out.linear, 0.0);
  EXPECT_EQ(out.angular, 0.0);
  out = limiter.limit({0.3, -kInf}, 10.0);
  EXPECT_DOUBLE_EQ(out.linear, 0.3);
  EXPECT_EQ(out.angular, 0.0);
}

TEST(VelocityLimiter, StopIsImmediateAndTheNextCommandRampsUp) {
  VelocityLimiter limiter;
  limiter.limit({0.7, 3.0}, 10.0);
  const Twist2D stopped = limiter.stop();
  EXPECT_EQ(stopped.linear, 0.0);
  EXPECT_EQ(stopped.angular, 0.0);
  EXPECT_EQ(limiter.lastOutput().linear, 0.0);
  EXPECT_NEAR(limiter.limit({0.7, 3.0}, 0.1).linear, 0.1, 1e-12);
}

TEST(VelocityLimiter, ResetForgetsThePreviousOutput) {
  VelocityLimiter limiter;
  limiter.limit({0.7, 3.0}, 10.0);
  limiter.reset();
  EXPECT_EQ(limiter.lastOutput().linear, 0.0);
  EXPECT_EQ(limiter.lastOutput().angular, 0.0);
  EXPECT_NEAR(limiter.limit({0.7, 0.0}, 0.1).linear, 0.1, 1e-12);
}

TEST(VelocityLimiter, OutputIsAlwaysFiniteAndWithinBounds) {
  VelocityLimiterConfig config;
  config.allow_reverse = true;
  VelocityLimiter limiter(config);
  GarbageNumbers garbage(7, 0.7);
  const auto draw = [&] { return garbage.maybe(garbage.uniform(-5.0, 5.0)); };
  Twist2D previous;
  for (int i = 0; i < 20000; ++i) {
    const double dt = draw();
    const Twist2D out = limiter.limit({draw(), draw()}, dt);
    ASSERT_TRUE(std::isfinite(out.linear) && std::isfinite(out.angular));
    ASSERT_LE(std::abs(out.linear), config.max_linear);
    ASSERT_LE(std::abs(out.angular), config.max_angular);
    if (std::isfinite(dt) && dt > 0.0) {
      ASSERT_LE(std::abs(out.linear - previous.linear), config.max_linear_accel * dt + 1e-12);
      ASSERT_LE(std::abs(out.angular - previous.angular), config.max_angular_accel * dt + 1e-12);
    } else {
      ASSERT_LE(std::abs(out.linear), std::abs(previous.linear));
      ASSERT_LE(std::abs(out.angular), std::abs(previous.angular));
    }
    previous = out;
  }
}

}  // namespace
}  // namespace follow_bot_common
