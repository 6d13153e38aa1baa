#include "follow_bot_common/frame_watchdog.h"

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>

namespace follow_bot {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(FrameWatchdog, RejectsUnusableTimeouts) {
  for (double bad : {0.0, -1.0, kNaN, kInf}) {
    EXPECT_THROW(FrameWatchdog{bad}, std::invalid_argument) << bad;
  }
  EXPECT_DOUBLE_EQ(FrameWatchdog(0.5).timeout(), 0.5);
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

}  // namespace
}  // namespace follow_bot
