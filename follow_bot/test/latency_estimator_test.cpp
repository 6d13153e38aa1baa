#include "follow_bot/latency_estimator.h"

#include <cmath>
#include <optional>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

namespace follow_bot {
namespace {

// A differential base driven by a follower-like command stream: it starts from rest with an
// acceleration limit, then weaves. It executes each command `delay` s after the frame it was
// made from, through a first-order lag of time constant `lag` s, and its odometry reports the
// mean motion over each odometry period.
struct Base {
  double frame_rate = 30.0;        // Hz
  double odom_rate = 30.0;         // Hz
  double odom_offset = 0.0;        // s after each frame's stamp (the harness: together)
  double delay = 0.0;              // s
  double lag = 0.0;                // s
  double odom_noise = 0.0;         // standard deviation, m/s and rad/s
  bool ramps = true;               // starts from rest, else at full speed
  double acceleration = 0.5;       // m/s^2 of the start
  bool weaves = true;              // else it drives straight
  bool odom_before_start = false;  // odometry reads the base at rest before the first frame
  double duration = 6.0;           // s

  // The command made from the frame at t.
  Twist2D command(double t) const {
    return {ramps ? std::min(0.3, acceleration * t) : 0.3,
            weaves ? 0.8 * std::sin(2.0 * M_PI * 0.3 * t) : 0.0};
  }

  // Feeds `estimator` the frames' commands and the odometry, in stamp order.
  void drive(LatencyEstimator& estimator) const {
    constexpr double kStep = 1e-4;  // s, the base's integration step
    std::mt19937 random(7);
    std::normal_distribution<double> noise(0.0, odom_noise);
    const double frame_period = 1.0 / frame_rate;
    const double odom_period = 1.0 / odom_rate;
    Twist2D applied;  // after the lag
    Twist2D sum;      // of applied since the last odometry
    int samples = 0;
    int next_frame = 0;
    int next_odom = 1;
    const auto held = [&](double t) {  // the command the base executes at t
      const double made = t - delay;
      return made < 0.0 ? Twist2D() : command(std::floor(made / frame_period) * frame_period);
    };
    if (odom_before_start) estimator.measured(-odom_period, {});
    for (double t = 0.0; t < duration; t += kStep) {
      if (t >= next_frame * frame_period - 1e-9) {
        const double stamp = next_frame * frame_period;
        estimator.commandSent(stamp, command(stamp));
        ++next_frame;
      }
      if (t >= next_odom * odom_period + odom_offset - 1e-9) {
        estimator.measured(
            next_odom * odom_period + odom_offset,
            {sum.linear / samples + noise(random), sum.angular / samples + noise(random)});
        sum = Twist2D();
        samples = 0;
        ++next_odom;
      }
      const Twist2D target = held(t);
      const double alpha = lag > 0.0 ? kStep / lag : 1.0;
      applied.linear += alpha * (target.linear - applied.linear);
      applied.angular += alpha * (target.angular - applied.angular);
      sum.linear += applied.linear;
      sum.angular += applied.angular;
      ++samples;
    }
  }
};

std::optional<double> measure(const Base& base) {
  LatencyEstimator estimator;
  base.drive(estimator);
  return estimator.latency();
}

// The harness's simulated base acts on a command at once, its odometry published with each
// frame: no delay at all to steer ahead by.
TEST(LatencyEstimatorTest, ABaseWithoutDelayMeasuresZero) {
  const std::optional<double> latency = measure(Base{});
  ASSERT_TRUE(latency);
  EXPECT_NEAR(*latency, 0.0, 1e-9);
}

TEST(LatencyEstimatorTest, PureDelaysAreMeasuredToAFewMilliseconds) {
  for (const double delay : {0.033, 0.05, 0.1, 0.15, 0.3}) {
    Base base;
    base.delay = delay;
    base.odom_rate = 50.0;  // odometry on its own clock
    base.odom_offset = 0.007;
    const std::optional<double> latency = measure(base);
    ASSERT_TRUE(latency) << delay;
    EXPECT_NEAR(*latency, delay, 0.005) << delay;
  }
}

TEST(LatencyEstimatorTest, AFifteenHertzCameraAndNoisyOdometry) {
  Base base;
  base.frame_rate = 15.0;
  base.odom_rate = 20.0;
  base.odom_offset = 0.013;
  base.delay = 0.12;
  base.odom_noise = 0.01;
  const std::optional<double> latency = measure(base);
  ASSERT_TRUE(latency);
  EXPECT_NEAR(*latency, 0.12, 0.01);
}

// A motor lag of time constant T delays a ramp by T and a slow weave by about T: the estimate
// is the delay plus about T, where the commands in flight take effect.
TEST(LatencyEstimatorTest, AMotorLagReadsAsMoreDelay) {
  for (const double lag : {0.1, 0.2}) {
    Base base;
    base.delay = 0.1;
    base.lag = lag;
    const std::optional<double> latency = measure(base);
    ASSERT_TRUE(latency) << lag;
    EXPECT_NEAR(*latency, 0.1 + lag, 0.02) << lag;
  }
}

// Odometry that shows the base at rest before the first command lets its start be measured at
// once (the first curve may be many seconds away).
TEST(LatencyEstimatorTest, AStartFromRestIsMeasuredWithinASecond) {
  for (const bool at_rest_before : {false, true}) {
    Base base;
    base.delay = 0.1;
    base.weaves = false;
    base.acceleration = 1.0;  // at full speed after 0.3 s
    base.odom_before_start = at_rest_before;
    base.duration = 1.0;
    const std::optional<double> latency = measure(base);
    ASSERT_EQ(latency.has_value(), at_rest_before);
    if (latency) EXPECT_NEAR(*latency, 0.1, 0.005);
  }
}

TEST(LatencyEstimatorTest, MotionThatNeverVariesTellsNothing) {
  Base base;
  base.ramps = false;
  base.weaves = false;
  base.delay = 0.1;
  EXPECT_FALSE(measure(base));
}

TEST(LatencyEstimatorTest, ABaseThatDoesNotMoveTellsNothing) {
  LatencyEstimator estimator;
  for (int k = 0; k < 300; ++k) {
    const double t = k / 30.0;
    estimator.commandSent(t, {0.2, std::sin(t)});
    estimator.measured(t, {});
  }
  EXPECT_FALSE(estimator.latency());
}

TEST(LatencyEstimatorTest, ARestartForgetsTheEstimateAndNonFiniteInputIsIgnored) {
  Base base;
  base.delay = 0.1;
  LatencyEstimator estimator;
  base.drive(estimator);
  ASSERT_TRUE(estimator.latency());
  estimator.commandSent(NAN, {0.1, 0.0});
  estimator.commandSent(100.0, {NAN, 0.0});
  estimator.measured(100.0, {INFINITY, 0.0});
  EXPECT_NEAR(*estimator.latency(), 0.1, 0.005);
  estimator.commandSent(0.0, {});  // the stamps start again
  EXPECT_FALSE(estimator.latency());
}

TEST(LatencyEstimatorTest, ValidateNamesTheBadField) {
  LatencyEstimatorConfig config;
  EXPECT_EQ(validate(config), "");
  config.max_unexplained = 1.5;
  EXPECT_EQ(validate(config), "max_unexplained must be in [0, 1], got 1.5");
  config = LatencyEstimatorConfig();
  config.resolution = 0.0;
  EXPECT_THROW(LatencyEstimator{config}, std::invalid_argument);
}

}  // namespace
}  // namespace follow_bot
