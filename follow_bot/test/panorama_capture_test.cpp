#include "follow_bot/panorama_capture.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace follow_bot {
namespace {

constexpr double kPi = 3.141592653589793;

// Integrates the commanded turn rate at 30 frames per second until the capture finishes.
struct CaptureRun {
  std::vector<double> grabbed_yaws;
  double final_yaw = 0.0;
  int frames = 0;
};

CaptureRun simulate(PanoramaCapture& capture, double start_yaw) {
  CaptureRun run;
  double yaw = start_yaw;
  capture.start(start_yaw);
  for (; run.frames < 100000; ++run.frames) {
    const PanoramaCapture::Step step = capture.update(yaw);
    EXPECT_LE(std::abs(step.angular), capture.config().max_turn_rate + 1e-12);
    if (step.grab) run.grabbed_yaws.push_back(yaw);
    if (step.finished) break;
    yaw = wrapAngle(yaw + step.angular / 30.0);
  }
  run.final_yaw = yaw;
  return run;
}

TEST(PanoramaCapture, GrabsEvenlySpacedHeadingsLeftToRightAndReturns) {
  PanoramaCapture capture;  // 120 deg in steps of 20 deg
  const CaptureRun run = simulate(capture, 0.3);
  ASSERT_EQ(run.grabbed_yaws.size(), 7u);
  for (std::size_t i = 0; i < run.grabbed_yaws.size(); ++i) {
    const double expected = 0.3 + kPi / 3.0 - i * kPi / 9.0;
    EXPECT_NEAR(run.grabbed_yaws[i], expected, capture.config().yaw_tolerance);
    EXPECT_NEAR(capture.headings()[i], expected, 1e-9);
  }
  EXPECT_NEAR(run.final_yaw, 0.3, capture.config().yaw_tolerance);
  EXPECT_FALSE(capture.active());
  EXPECT_LT(run.frames, 30 * 20);  // well under 20 s of turning at 30 Hz
}

TEST(PanoramaCapture, WrapsAroundPlusMinusPi) {
  PanoramaCaptureConfig config;
  config.return_to_start = false;
  PanoramaCapture capture(config);
  const CaptureRun run = simulate(capture, kPi - 0.1);
  ASSERT_EQ(run.grabbed_yaws.size(), 7u);
  EXPECT_NEAR(wrapAngle(run.grabbed_yaws.front() - (kPi - 0.1 + kPi / 3.0)), 0.0, 0.01);
  EXPECT_NEAR(wrapAngle(run.final_yaw - (kPi - 0.1 - kPi / 3.0)), 0.0, 0.01);
}

TEST(PanoramaCapture, StepNeverExceedsTheConfiguredAngle) {
  PanoramaCaptureConfig config;
  config.total_angle = 1.0;
  config.step_angle = 0.3;  // 1.0 / 0.3 -> 4 intervals of 0.25
  PanoramaCapture capture(config);
  capture.start(0.0);
  ASSERT_EQ(capture.headings().size(), 5u);
  EXPECT_NEAR(capture.headings()[0] - capture.headings()[1], 0.25, 1e-12);
}

TEST(PanoramaCapture, IdleCaptureCommandsNothing) {
  PanoramaCapture capture;
  const PanoramaCapture::Step step = capture.update(1.0);
  EXPECT_EQ(step.angular, 0.0);
  EXPECT_FALSE(step.grab);
  EXPECT_FALSE(step.finished);
}

TEST(PanoramaCapture, RejectsUnusableConfigurations) {
  const auto error_with = [](double PanoramaCaptureConfig::*member, double value) {
    PanoramaCaptureConfig config;
    config.*member = value;
    return validate(config);
  };
  EXPECT_EQ(validate(PanoramaCaptureConfig()), "");
  EXPECT_EQ(error_with(&PanoramaCaptureConfig::total_angle, 7.0),
            "total_angle must be in (0, 2 pi) rad");
  EXPECT_EQ(error_with(&PanoramaCaptureConfig::step_angle, 0.0),
            "step_angle must be in (0, total_angle] rad");
  EXPECT_EQ(error_with(&PanoramaCaptureConfig::yaw_gain, 0.0), "yaw_gain must be > 0, got 0");
  EXPECT_EQ(error_with(&PanoramaCaptureConfig::min_turn_rate, 5.0),
            "min_turn_rate must be in (0, max_turn_rate] rad/s");
  EXPECT_EQ(error_with(&PanoramaCaptureConfig::yaw_tolerance, 0.5),
            "yaw_tolerance must be in (0, step_angle / 2) rad");
  PanoramaCaptureConfig config;
  config.total_angle = 7.0;
  EXPECT_THROW(PanoramaCapture{config}, std::invalid_argument);
}

TEST(YawOfQuaternion, ReadsUnitQuaternionsAndRejectsTheRest) {
  EXPECT_NEAR(yawOfQuaternion(0.0, 0.0, std::sin(0.4), std::cos(0.4)), 0.8, 1e-12);
  EXPECT_NEAR(yawOfQuaternion(0.0, 0.0, 1.0, 0.0), kPi, 1e-12);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  // Each of these gave a finite heading from atan2 alone (pi for the first).
  for (const auto& q : {std::array<double, 4>{0.0, 0.0, 1e300, 0.0},
                        {0.0, 0.0, 0.0, 0.0},
                        {0.0, 0.0, 0.0, 2.0},
                        {nan, 0.0, 0.0, 1.0},
                        {0.0, 0.0, inf, inf}}) {
    EXPECT_TRUE(std::isnan(yawOfQuaternion(q[0], q[1], q[2], q[3])))
        << q[0] << " " << q[1] << " " << q[2] << " " << q[3];
  }
}

}  // namespace
}  // namespace follow_bot
