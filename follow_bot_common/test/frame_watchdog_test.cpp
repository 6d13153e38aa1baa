#include "follow_bot_common/frame_watchdog.h"

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>
#include <vector>

namespace follow_bot_common {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(FrameWatchdog, RejectsUnusableTimeouts) {
  for (double bad : {0.0, -1.0, kNaN, kInf}) {
    EXPECT_THROW(FrameWatchdog{bad}, std::invalid_argument) << bad;
  }
  EXPECT_DOUBLE_EQ(FrameWatchdog(0.5).timeout(), 0.5);
  for (double bad : {-0.1, kNaN, kInf}) {
    EXPECT_THROW((FrameWatchdog{0.5, bad}), std::invalid_argument) << bad;
  }
}

TEST(FrameWatchdog, BeforeTheFirstFrameIsExpiredButSendsNoStop) {
  FrameWatchdog watchdog(0.5);
  EXPECT_TRUE(watchdog.expired(10.0));
  EXPECT_FALSE(watchdog.shouldSendStop(10.0));
}

TEST(FrameWatchdog, SendsOneStopPerOutage) {
  FrameWatchdog watchdog(0.5);
  int stops = 0;
  // Frames every 0.1 s until t = 1.0, a gap until t = 3.0, frames again, then a final gap.
  for (int tick = 0; tick <= 600; ++tick) {  // 10 ms timer ticks over 6 s
    const double now = tick * 0.01;
    const bool camera_up = now <= 1.0 + 1e-9 || (now >= 3.0 - 1e-9 && now <= 4.0 + 1e-9);
    if (camera_up && tick % 10 == 0) watchdog.frameArrived(now);
    if (watchdog.shouldSendStop(now)) {
      ++stops;
      const double outage_start = stops == 1 ? 1.5 : 4.5;  // last frame + timeout
      EXPECT_TRUE(now >= outage_start && now < outage_start + 0.03) << now;
    }
    if (now > 1.55 && now < 2.99) {
      EXPECT_TRUE(watchdog.expired(now)) << now;
    }
    if (now > 3.0 && now < 4.0) {
      EXPECT_FALSE(watchdog.expired(now)) << now;
    }
  }
  EXPECT_EQ(stops, 2);
}

TEST(FrameWatchdog, ExpiresOnlyAfterTheTimeout) {
  FrameWatchdog watchdog(0.5);
  watchdog.frameArrived(2.0);
  EXPECT_FALSE(watchdog.expired(2.0));
  EXPECT_FALSE(watchdog.expired(2.5));
  EXPECT_TRUE(watchdog.expired(2.5001));
  EXPECT_FALSE(watchdog.shouldSendStop(2.5));
  EXPECT_TRUE(watchdog.shouldSendStop(2.6));
  EXPECT_FALSE(watchdog.shouldSendStop(2.7));
  EXPECT_FALSE(watchdog.shouldSendStop(100.0));
}

TEST(FrameWatchdog, ClockJumpingBackCountsAsAnOutage) {
  FrameWatchdog watchdog(0.5);
  watchdog.frameArrived(100.0);
  EXPECT_TRUE(watchdog.expired(1.0));
  EXPECT_TRUE(watchdog.shouldSendStop(1.0));
  watchdog.frameArrived(1.02);  // frames on the new clock end the outage
  EXPECT_FALSE(watchdog.expired(1.05));
}

TEST(FrameWatchdog, HandlesNonFiniteTimes) {
  FrameWatchdog watchdog(0.5);
  watchdog.frameArrived(1.0);
  watchdog.frameArrived(kNaN);  // ignored
  EXPECT_FALSE(watchdog.expired(1.2));
  EXPECT_TRUE(watchdog.expired(kNaN));
  EXPECT_TRUE(watchdog.expired(kInf));
  EXPECT_TRUE(watchdog.shouldSendStop(kNaN));
}

TEST(FrameWatchdog, ResetForgetsFramesAndOutages) {
  FrameWatchdog watchdog(0.5);
  watchdog.frameArrived(1.0);
  watchdog.reset();
  EXPECT_TRUE(watchdog.expired(1.1));
  EXPECT_FALSE(watchdog.shouldSendStop(5.0));
}

// Frames every `period` s from t = 0 until `end`, watched on 10 ms timer ticks until `until`;
// returns the times of the stops.
std::vector<double> stopsForCamera(FrameWatchdog& watchdog, double period, double end,
                                   double until) {
  std::vector<double> stops;
  double next_frame = 0.0;
  for (int tick = 0; tick * 0.01 <= until + 1e-9; ++tick) {
    const double now = tick * 0.01;
    if (now >= next_frame - 1e-9 && now <= end + 1e-9) {
      watchdog.frameArrived(now);
      next_frame += period;
    }
    if (watchdog.shouldSendStop(now)) stops.push_back(now);
  }
  return stops;
}

TEST(FrameWatchdog, ASlowCameraIsNoOutageBetweenFramesButStillStopsWhenFramesEnd) {
  // 5 Hz, its period known: no stop in 10 s of frames, one within 3 periods of the last.
  FrameWatchdog watchdog(0.15, 0.2);
  EXPECT_DOUBLE_EQ(watchdog.timeout(), 0.6);
  const std::vector<double> stops = stopsForCamera(watchdog, 0.2, 10.0, 12.0);
  ASSERT_EQ(stops.size(), 1u);
  EXPECT_GT(stops[0], 10.6 - 1e-9);
  EXPECT_LT(stops[0], 10.6 + 0.011);
  EXPECT_NEAR(watchdog.frameInterval(), 0.2, 1e-9);
}

TEST(FrameWatchdog, AnUnknownRateIsMeasuredFromTheSecondFrame) {
  // Until two frames gave an interval the minimum holds: the first 0.2 s gap is an outage (no
  // command has had time to go out yet), every later one is not.
  FrameWatchdog watchdog(0.15);
  const std::vector<double> stops = stopsForCamera(watchdog, 0.2, 10.0, 12.0);
  ASSERT_EQ(stops.size(), 2u);
  EXPECT_NEAR(stops[0], 0.16, 1e-9);
  EXPECT_GT(stops[1], 10.6 - 1e-9);
  EXPECT_LT(stops[1], 10.6 + 0.011);
}

TEST(FrameWatchdog, AFastCameraKeepsTheMinimumTimeout) {
  FrameWatchdog watchdog(0.15, 1.0 / 30.0);
  EXPECT_DOUBLE_EQ(watchdog.timeout(), 0.15);
  const std::vector<double> stops = stopsForCamera(watchdog, 1.0 / 30.0, 3.0, 4.0);
  EXPECT_DOUBLE_EQ(watchdog.timeout(), 0.15);  // 3 x 33 ms is below the minimum
  ASSERT_EQ(stops.size(), 1u);
  EXPECT_GT(stops[0], 2.96 + 0.15);
  EXPECT_LT(stops[0], 3.0 + 0.16 + 1e-9);
}

TEST(FrameWatchdog, OneLongGapDoesNotLengthenTheTimeout) {
  FrameWatchdog watchdog(0.15);
  for (int k = 0; k <= 30; ++k) watchdog.frameArrived(k * 0.04);
  watchdog.frameArrived(1.2 + 2.0);  // a 2 s outage
  for (int k = 1; k <= 3; ++k) watchdog.frameArrived(3.2 + k * 0.04);
  EXPECT_DOUBLE_EQ(watchdog.timeout(), 0.15);
  EXPECT_NEAR(watchdog.frameInterval(), 0.04, 1e-9);
}

TEST(FrameWatchdog, ALastingSlowdownLengthensTheTimeoutWithinHalfTheWindow) {
  FrameWatchdog watchdog(0.15);
  double t = 0.0;
  for (int k = 0; k < 30; ++k) watchdog.frameArrived(t += 1.0 / 30.0);
  int frames_until_adapted = 0;
  while (watchdog.timeout() < 0.6 - 1e-9) {
    watchdog.frameArrived(t += 0.2);
    ++frames_until_adapted;
  }
  EXPECT_EQ(frames_until_adapted, FrameWatchdog::kWindow / 2 + 1);
}

TEST(FrameWatchdog, ProofOfLifeEndsAnOutageWithoutMeasuringAnInterval) {
  FrameWatchdog watchdog(0.15);
  watchdog.frameArrived(1.0);
  watchdog.frameArrived(1.1);
  watchdog.aliveAt(1.12);  // the work on the frame ended
  EXPECT_NEAR(watchdog.frameInterval(), 0.1, 1e-9);
  EXPECT_FALSE(watchdog.expired(1.12 + 0.29));
  EXPECT_TRUE(watchdog.expired(1.12 + 0.31));
  watchdog.frameArrived(1.2);  // measured from the last frame, not from the proof of life
  EXPECT_NEAR(watchdog.frameInterval(), 0.1, 1e-9);
}

TEST(FrameWatchdog, ResetForgetsTheMeasuredRate) {
  FrameWatchdog watchdog(0.15);
  watchdog.frameArrived(1.0);
  watchdog.frameArrived(2.0);
  EXPECT_DOUBLE_EQ(watchdog.timeout(), 3.0);
  watchdog.reset();
  EXPECT_DOUBLE_EQ(watchdog.timeout(), 0.15);
  EXPECT_DOUBLE_EQ(watchdog.frameInterval(), 0.0);
}

}  // namespace
}  // namespace follow_bot_common
