#include "follow_bot/line_controller.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "follow_bot/common.h"
#include "follow_bot_common/testing/garbage_numbers.h"

namespace follow_bot {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kWidth = 640;

BandMeasurement bandAt(double centroid_x, int pixel_count = 200, double confidence = 1.0) {
  BandMeasurement band;
  band.pixel_count = pixel_count;
  band.found = pixel_count >= 30;
  band.centroid_x = centroid_x;
  band.centroid_y = 370.0;
  band.error_px = centroid_x - kWidth / 2.0;
  band.error_normalised = band.error_px / (kWidth / 2.0);
  band.confidence = confidence;
  return band;
}

LineMeasurement seen(double centroid_x) {
  LineMeasurement m;
  m.image_width = kWidth;
  m.image_height = 480;
  m.band = bandAt(centroid_x);
  return m;
}

// A line at normalised error e.
LineMeasurement seenAtError(double e) { return seen(kWidth / 2.0 * (1.0 + e)); }

LineMeasurement unseen() {
  LineMeasurement m;
  m.image_width = kWidth;
  m.image_height = 480;
  return m;
}

TEST(LectureLaw, IsTheLectureLaw) {
  LectureLaw controller;
  for (double cx : {0.0, 100.0, 319.5, 320.0, 321.25, 500.0, 639.0}) {
    const Twist2D twist = controller.step({seen(cx), 0.0});
    EXPECT_EQ(twist.linear, 0.2);
    EXPECT_EQ(twist.angular, -(cx - 320.0) / 100.0) << cx;
    EXPECT_EQ(controller.state(), LineState::kFollowing);
  }
}

TEST(LectureLaw, NeedsOnlyOnePixelAndIgnoresConfidence) {
  LectureLaw controller;
  LineMeasurement few = seen(420.0);
  few.band = bandAt(420.0, 1, 0.0);  // below min_pixels, zero confidence: the lecture follows
  const Twist2D twist = controller.step({few, 0.0});
  EXPECT_EQ(twist.linear, 0.2);
  EXPECT_EQ(twist.angular, -1.0);
}

TEST(LectureLaw, StopsWithoutPixels) {
  LectureLaw controller;
  controller.step({seen(400.0), 0.0});
  const Twist2D twist = controller.step({unseen(), 0.1});
  EXPECT_EQ(twist.linear, 0.0);
  EXPECT_EQ(twist.angular, 0.0);
  EXPECT_EQ(controller.state(), LineState::kLost);
  LineMeasurement rejected = seen(400.0);
  rejected.error = "empty image";
  EXPECT_EQ(controller.step({rejected, 0.2}).linear, 0.0);
}

// End to end: a frame through the detector and the lecture controller gives the command of the
// lecture's own pipeline (full-frame HSV, inRange, row blanking, cv::moments).
TEST(LectureLaw, ReproducesTheLecturePipeline) {
  cv::Mat frame(480, 640, CV_8UC3, cv::Scalar(110, 115, 120));
  cv::line(frame, cv::Point(200, 479), cv::Point(450, 250), cv::Scalar(0, 220, 230), 25,
           cv::LINE_AA);
  cv::Mat hsv, mask;
  cv::cvtColor(frame, hsv, cv::COLOR_BGR2HSV);
  cv::inRange(hsv, cv::Scalar(20, 100, 100), cv::Scalar(30, 255, 255), mask);
  for (int y = 0; y < 480; ++y) {
    if (y < 360 || y >= 380) mask.row(y).setTo(0);
  }
  const cv::Moments moments = cv::moments(mask);
  ASSERT_GT(moments.m00, 0);
  const double err = moments.m10 / moments.m00 - 640 / 2;

  LectureLaw controller;
  const Twist2D twist = controller.step({LineDetector().detect(frame), 0.0});
  EXPECT_EQ(twist.linear, 0.2);
  EXPECT_DOUBLE_EQ(twist.angular, -err / 100);
}

TEST(PdLaw, SteersTowardTheLine) {
  PdLaw controller;
  const Twist2D right = controller.step({seenAtError(0.5), 0.0});
  EXPECT_LT(right.angular, 0.0) << "line right of centre: turn right (clockwise)";
  EXPECT_NEAR(right.angular, -1.5 * 0.5, 1e-12);  // first frame: P only

  controller.reset();
  const Twist2D left = controller.step({seenAtError(-0.5), 0.0});
  EXPECT_GT(left.angular, 0.0);

  controller.reset();
  const Twist2D centred = controller.step({seenAtError(0.0), 0.0});
  EXPECT_EQ(centred.angular, 0.0);
  EXPECT_DOUBLE_EQ(centred.linear, 0.3);
  EXPECT_EQ(controller.state(), LineState::kFollowing);
}

TEST(PdLaw, DerivativeUsesFrameStamps) {
  SteeringConfig config;
  config.pd.kp = 0.0;
  config.pd.kd = 0.1;
  PdLaw controller(config);
  controller.step({seenAtError(0.1), 10.0});
  // e rises by 0.2 in 0.1 s: de/dt = 2, angular = -0.1 * 2.
  EXPECT_NEAR(controller.step({seenAtError(0.3), 10.1}).angular, -0.2, 1e-9);
  // The same rise in 0.05 s doubles it.
  EXPECT_NEAR(controller.step({seenAtError(0.5), 10.15}).angular, -0.4, 1e-9);
  // A repeated stamp (dt = 0) or a stale previous frame gives no derivative.
  EXPECT_EQ(controller.step({seenAtError(0.7), 10.15}).angular, 0.0);
  EXPECT_EQ(controller.step({seenAtError(0.1), 11.0}).angular, 0.0);
}

TEST(PdLaw, NoDerivativeKickWhenTheLineReturns) {
  SteeringConfig config;
  config.pd.kp = 0.0;
  PdLaw controller(config);
  controller.step({seenAtError(-0.8), 0.0});
  controller.step({unseen(), 0.05});
  EXPECT_EQ(controller.step({seenAtError(0.8), 0.1}).angular, 0.0);
}

TEST(PdLaw, SpeedTapersWithError) {
  PdLaw controller;  // max 0.3, min 0.05, taper 0.6
  double previous_speed = 1.0;
  for (double e : {0.0, 0.2, 0.4, 0.6, 0.8, 1.0}) {
    controller.reset();
    const double speed = controller.step({seenAtError(e), 0.0}).linear;
    EXPECT_NEAR(speed, std::max(0.05, 0.3 * (1.0 - 0.6 * e)), 1e-9) << e;
    EXPECT_LE(speed, previous_speed);
    previous_speed = speed;
  }
  SteeringConfig steep;
  steep.pd.taper = 2.0;
  PdLaw clamped(steep);
  EXPECT_DOUBLE_EQ(clamped.step({seenAtError(0.9), 0.0}).linear, 0.05);
}

TEST(PdLaw, BlendsTheLookAheadBandAndSlowsForCurves) {
  SteeringConfig config;
  config.pd.kd = 0.0;
  PdLaw controller(config);
  LineMeasurement m = seenAtError(0.1);
  m.look_ahead = bandAt(kWidth / 2.0 * (1.0 + 0.5));  // e_ahead = 0.5
  const Twist2D twist = controller.step({m, 0.0});
  const double blended = 0.7 * 0.1 + 0.3 * 0.5;
  EXPECT_NEAR(twist.angular, -1.5 * blended, 1e-9);
  EXPECT_NEAR(twist.linear, 0.3 * (1.0 - 0.6 * blended - 0.5 * 0.4), 1e-9);

  // An unconfident look-ahead band is ignored.
  m.look_ahead.confidence = 0.1;
  controller.reset();
  EXPECT_NEAR(controller.step({m, 0.0}).angular, -1.5 * 0.1, 1e-9);
}

TEST(PdLaw, LostThenSearchingThenGivesUpThenResumes) {
  PdLaw controller;                          // grace 1 s, search 12 s
  controller.step({seenAtError(0.6), 0.0});  // last seen on the right

  // Frames without the line: the state after each and its command.
  struct Unseen {
    double stamp;
    LineState state;
    Twist2D command;
  };
  for (const Unseen& frame : {
           Unseen{0.5, LineState::kLost, {0.05, -0.4}},  // creeps on, turning toward it
           Unseen{1.0, LineState::kLost, {0.05, -0.4}},
           Unseen{1.01, LineState::kSearching, {0.0, -0.6}},  // turns on the spot
           Unseen{13.0, LineState::kSearching, {0.0, -0.6}},
           Unseen{13.01, LineState::kGaveUp, {0.0, 0.0}},
           Unseen{500.0, LineState::kGaveUp, {0.0, 0.0}},
       }) {
    const Twist2D command = controller.step({unseen(), frame.stamp});
    EXPECT_EQ(controller.state(), frame.state) << frame.stamp;
    EXPECT_DOUBLE_EQ(command.linear, frame.command.linear) << frame.stamp;
    EXPECT_DOUBLE_EQ(command.angular, frame.command.angular) << frame.stamp;
  }

  const Twist2D twist = controller.step({seenAtError(-0.2), 501.0});
  EXPECT_EQ(controller.state(), LineState::kFollowing);
  EXPECT_GT(twist.angular, 0.0);
  // Lost again, now on the left: the search turns left.
  controller.step({unseen(), 501.5});
  EXPECT_EQ(controller.state(), LineState::kLost);
  EXPECT_DOUBLE_EQ(controller.step({unseen(), 503.0}).angular, 0.6);
}

TEST(PdLaw, WithoutEverSeeingTheLineSearchesThenGivesUp) {
  PdLaw controller;
  Twist2D twist = controller.step({unseen(), 100.0});
  EXPECT_EQ(controller.state(), LineState::kSearching);
  EXPECT_EQ(twist.linear, 0.0);
  EXPECT_DOUBLE_EQ(twist.angular, 0.6);
  controller.step({unseen(), 112.0});
  EXPECT_EQ(controller.state(), LineState::kSearching);
  controller.step({unseen(), 112.1});
  EXPECT_EQ(controller.state(), LineState::kGaveUp);
}

TEST(PdLaw, LowConfidenceOrRejectedFramesCountAsUnseen) {
  PdLaw controller;
  controller.step({seenAtError(0.3), 0.0});
  LineMeasurement faint = seenAtError(0.3);
  faint.band.confidence = 0.1;
  controller.step({faint, 0.1});
  EXPECT_EQ(controller.state(), LineState::kLost);
  LineMeasurement rejected = seenAtError(0.3);
  rejected.error = "empty image";
  controller.step({rejected, 0.2});
  EXPECT_EQ(controller.state(), LineState::kLost);
}

TEST(PdLaw, ClockJumpingBackResets) {
  PdLaw controller;
  controller.step({seenAtError(0.5), 100.0});
  controller.step({unseen(), 150.0});
  EXPECT_EQ(controller.state(), LineState::kGaveUp);
  // Sim restart: time goes back; the controller starts afresh instead of computing
  // negative intervals.
  controller.step({unseen(), 1.0});
  EXPECT_EQ(controller.state(), LineState::kSearching);
}

TEST(PdLaw, ADenormalIntervalGivesNoDerivative) {
  SteeringConfig config;
  config.pd.kd = 0.0;  // an infinite error rate would give 0 * inf = NaN
  PdLaw controller(config);
  controller.step({seenAtError(-0.5), 0.0});
  const Twist2D twist = controller.step({seenAtError(0.5), 5e-324});
  EXPECT_DOUBLE_EQ(twist.angular, -1.5 * 0.5);
}

TEST(PdLaw, NeverOutputsNonFiniteValues) {
  GarbageNumbers garbage(3, 0.7);
  const auto draw = [&] { return garbage.maybe(garbage.uniform(-2.0, 2.0)); };
  for (const auto& [mode, kd] :
       {std::pair(SteeringMode::kPD, 0.1), std::pair(SteeringMode::kPD, 0.0),
        std::pair(SteeringMode::kLecture, 0.1)}) {
    SteeringConfig config;
    config.mode = mode;
    config.pd.kd = kd;  // with kd = 0, an infinite error rate would make 0 * inf = NaN
    const std::unique_ptr<SteeringLaw> controller = makeSteeringLaw(config, std::nullopt);
    double stamp = 0.0;
    for (int i = 0; i < 20000; ++i) {
      LineMeasurement m = seenAtError(garbage.uniform(-2.0, 2.0));
      m.band.found = garbage.chance(0.8);
      m.band.error_normalised = draw();
      m.band.error_px = draw();
      m.band.confidence = draw();
      m.look_ahead = bandAt(0.0);
      m.look_ahead.error_normalised = draw();
      stamp = garbage.chance(0.1) ? draw() : stamp + garbage.uniform(0.0, 2e-3);
      const Twist2D twist = controller->step({m, stamp});
      ASSERT_TRUE(std::isfinite(twist.linear) && std::isfinite(twist.angular)) << i;
    }
  }
}

}  // namespace
}  // namespace follow_bot
