#include "follow_bot_common/frame_rate_status.h"

#include <gtest/gtest.h>

namespace follow_bot_common {
namespace {

using Level = StatusReport::Level;

CameraHealth flowing(double interval, double expected_rate) {
  CameraHealth health;
  health.frames_seen = true;
  health.frames_flowing = true;
  health.interval = interval;
  health.expected_rate = expected_rate;
  health.timeout = 0.3;
  return health;
}

TEST(FrameRateStatus, ASteadyCameraIsOkAtItsExpectedRateOrAnUnknownOne) {
  for (double expected : {10.0, 0.0}) {
    const StatusReport report = frameRateStatus(flowing(0.1, expected));
    EXPECT_EQ(report.level, Level::kOk) << expected;
    EXPECT_EQ(report.message, "10.0 Hz");
  }
  EXPECT_EQ(frameRateStatus(flowing(1.0 / 11.9, 10.0)).level, Level::kOk);  // within 20 %
}

TEST(FrameRateStatus, WarnsWhenTheRateIsOffTheExpectedOne) {
  const StatusReport report = frameRateStatus(flowing(0.1, 30.0));
  EXPECT_EQ(report.level, Level::kWarn);
  EXPECT_EQ(report.message, "10.0 Hz, expected 30.0 Hz");
  EXPECT_EQ(frameRateStatus(flowing(1.0 / 12.1, 10.0)).level, Level::kWarn);
}

TEST(FrameRateStatus, NoFramesIsAnErrorOnlyWhenTheWatchdogStoppedTheRobot) {
  CameraHealth health = flowing(0.1, 0.0);
  health.frames_flowing = false;
  StatusReport report = frameRateStatus(health);
  EXPECT_EQ(report.level, Level::kWarn);
  EXPECT_EQ(report.message, "no frames, idle: nothing to stop");
  health.stopped_by_watchdog = true;
  report = frameRateStatus(health);
  EXPECT_EQ(report.level, Level::kError);
  EXPECT_EQ(report.message, "no frames: the watchdog stopped the robot");
  report = frameRateStatus(CameraHealth{});
  EXPECT_EQ(report.level, Level::kWarn);
  EXPECT_EQ(report.message, "no frames yet, idle");
}

TEST(FrameRateStatus, ReportsTheRatesAndTheTimeout) {
  const StatusReport report = frameRateStatus(flowing(0.2, 0.0));
  ASSERT_EQ(report.values.size(), 3u);
  EXPECT_EQ(report.values[0].second, "5.0");
  EXPECT_EQ(report.values[1].second, "unknown");
  EXPECT_EQ(report.values[2].second, "0.300");
  EXPECT_EQ(frameRateStatus(flowing(0.0, 0.0)).message, "frames arriving");
}

}  // namespace
}  // namespace follow_bot_common
