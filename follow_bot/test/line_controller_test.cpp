#include "follow_bot/line_controller.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>
#include <stdexcept>

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

LineControllerConfig lectureConfig() {
  LineControllerConfig config;
  config.mode = ControlMode::kLecture;
  return config;
}

TEST(LineController, LectureModeIsTheLectureLaw) {
  LineController controller(lectureConfig());
  for (double cx : {0.0, 100.0, 319.5, 320.0, 321.25, 500.0, 639.0}) {
    const Twist2D twist = controller.update(seen(cx), 0.0);
    EXPECT_EQ(twist.linear, 0.2);
    EXPECT_EQ(twist.angular, -(cx - 320.0) / 100.0) << cx;
    EXPECT_EQ(controller.state(), LineState::kFollowing);
  }
}

TEST(LineController, LectureModeNeedsOnlyOnePixelAndIgnoresConfidence) {
  LineController controller(lectureConfig());
  LineMeasurement few = seen(420.0);
  few.band = bandAt(420.0, 1, 0.0);  // below min_pixels, zero confidence: the lecture follows
  const Twist2D twist = controller.update(few, 0.0);
  EXPECT_EQ(twist.linear, 0.2);
  EXPECT_EQ(twist.angular, -1.0);
}

TEST(LineController, LectureModeStopsWithoutPixels) {
  LineController controller(lectureConfig());
  controller.update(seen(400.0), 0.0);
  const Twist2D twist = controller.update(unseen(), 0.1);
  EXPECT_EQ(twist.linear, 0.0);
  EXPECT_EQ(twist.angular, 0.0);
  EXPECT_EQ(controller.state(), LineState::kLost);
  LineMeasurement rejected = seen(400.0);
  rejected.error = "empty image";
  EXPECT_EQ(controller.update(rejected, 0.2).linear, 0.0);
}

// End to end: a frame through the detector and the lecture controller gives the command of the
// lecture's own pipeline (full-frame HSV, inRange, row blanking, cv::moments).
TEST(LineController, LectureModeReproducesTheLecturePipeline) {
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

  LineController controller(lectureConfig());
  const Twist2D twist = controller.update(LineDetector().detect(frame), 0.0);
  EXPECT_EQ(twist.linear, 0.2);
  EXPECT_DOUBLE_EQ(twist.angular, -err / 100);
}

TEST(LineController, PdSteersTowardTheLine) {
  LineController controller;
  const Twist2D right = controller.update(seenAtError(0.5), 0.0);
  EXPECT_LT(right.angular, 0.0) << "line right of centre: turn right (clockwise)";
  EXPECT_NEAR(right.angular, -1.5 * 0.5, 1e-12);  // first frame: P only

  controller.reset();
  const Twist2D left = controller.update(seenAtError(-0.5), 0.0);
  EXPECT_GT(left.angular, 0.0);

  controller.reset();
  const Twist2D centred = controller.update(seenAtError(0.0), 0.0);
  EXPECT_EQ(centred.angular, 0.0);
  EXPECT_DOUBLE_EQ(centred.linear, 0.3);
  EXPECT_EQ(controller.state(), LineState::kFollowing);
}

TEST(LineController, DerivativeUsesFrameStamps) {
  LineControllerConfig config;
  config.kp = 0.0;
  config.kd = 0.1;
  LineController controller(config);
  controller.update(seenAtError(0.1), 10.0);
  // e rises by 0.2 in 0.1 s: de/dt = 2, angular = -0.1 * 2.
  EXPECT_NEAR(controller.update(seenAtError(0.3), 10.1).angular, -0.2, 1e-9);
  // The same rise in 0.05 s doubles it.
  EXPECT_NEAR(controller.update(seenAtError(0.5), 10.15).angular, -0.4, 1e-9);
  // A repeated stamp (dt = 0) or a stale previous frame gives no derivative.
  EXPECT_EQ(controller.update(seenAtError(0.7), 10.15).angular, 0.0);
  EXPECT_EQ(controller.update(seenAtError(0.1), 11.0).angular, 0.0);
}

TEST(LineController, NoDerivativeKickWhenTheLineReturns) {
  LineControllerConfig config;
  config.kp = 0.0;
  LineController controller(config);
  controller.update(seenAtError(-0.8), 0.0);
  controller.update(unseen(), 0.05);
  EXPECT_EQ(controller.update(seenAtError(0.8), 0.1).angular, 0.0);
}

TEST(LineController, SpeedTapersWithError) {
  LineController controller;  // max 0.3, min 0.05, taper 0.6
  double previous_speed = 1.0;
  for (double e : {0.0, 0.2, 0.4, 0.6, 0.8, 1.0}) {
    controller.reset();
    const double speed = controller.update(seenAtError(e), 0.0).linear;
    EXPECT_NEAR(speed, std::max(0.05, 0.3 * (1.0 - 0.6 * e)), 1e-9) << e;
    EXPECT_LE(speed, previous_speed);
    previous_speed = speed;
  }
  LineControllerConfig steep;
  steep.taper = 2.0;
  LineController clamped(steep);
  EXPECT_DOUBLE_EQ(clamped.update(seenAtError(0.9), 0.0).linear, 0.05);
}

TEST(LineController, BlendsTheLookAheadBandAndSlowsForCurves) {
  LineControllerConfig config;
  config.kd = 0.0;
  LineController controller(config);
  LineMeasurement m = seenAtError(0.1);
  m.look_ahead = bandAt(kWidth / 2.0 * (1.0 + 0.5));  // e_ahead = 0.5
  const Twist2D twist = controller.update(m, 0.0);
  const double blended = 0.7 * 0.1 + 0.3 * 0.5;
  EXPECT_NEAR(twist.angular, -1.5 * blended, 1e-9);
  EXPECT_NEAR(twist.linear, 0.3 * (1.0 - 0.6 * blended - 0.5 * 0.4), 1e-9);

  // An unconfident look-ahead band is ignored.
  m.look_ahead.confidence = 0.1;
  controller.reset();
  EXPECT_NEAR(controller.update(m, 0.0).angular, -1.5 * 0.1, 1e-9);
}

TEST(LineController, LostThenSearchingThenGivesUpThenResumes) {
  LineController controller;                 // grace 1 s, search 12 s
  controller.update(seenAtError(0.6), 0.0);  // last seen on the right

  Twist2D twist = controller.update(unseen(), 0.5);
  EXPECT_EQ(controller.state(), LineState::kLost);
  EXPECT_DOUBLE_EQ(twist.linear, 0.05);
  EXPECT_DOUBLE_EQ(twist.angular, -0.4);
  controller.update(unseen(), 1.0);
  EXPECT_EQ(controller.state(), LineState::kLost);

  twist = controller.update(unseen(), 1.01);
  EXPECT_EQ(controller.state(), LineState::kSearching);
  EXPECT_EQ(twist.linear, 0.0);
  EXPECT_DOUBLE_EQ(twist.angular, -0.6);
  controller.update(unseen(), 13.0);
  EXPECT_EQ(controller.state(), LineState::kSearching);

  twist = controller.update(unseen(), 13.01);
  EXPECT_EQ(controller.state(), LineState::kGaveUp);
  EXPECT_EQ(twist.linear, 0.0);
  EXPECT_EQ(twist.angular, 0.0);
  controller.update(unseen(), 500.0);
  EXPECT_EQ(controller.state(), LineState::kGaveUp);

  twist = controller.update(seenAtError(-0.2), 501.0);
  EXPECT_EQ(controller.state(), LineState::kFollowing);
  EXPECT_GT(twist.angular, 0.0);
  // Lost again, now on the left: the search turns left.
  controller.update(unseen(), 501.5);
  EXPECT_EQ(controller.state(), LineState::kLost);
  EXPECT_DOUBLE_EQ(controller.update(unseen(), 503.0).angular, 0.6);
}

TEST(LineController, WithoutEverSeeingTheLineSearchesThenGivesUp) {
  LineController controller;
  Twist2D twist = controller.update(unseen(), 100.0);
  EXPECT_EQ(controller.state(), LineState::kSearching);
  EXPECT_EQ(twist.linear, 0.0);
  EXPECT_DOUBLE_EQ(twist.angular, 0.6);
  controller.update(unseen(), 112.0);
  EXPECT_EQ(controller.state(), LineState::kSearching);
  controller.update(unseen(), 112.1);
  EXPECT_EQ(controller.state(), LineState::kGaveUp);
}

TEST(LineController, LowConfidenceOrRejectedFramesCountAsUnseen) {
  LineController controller;
  controller.update(seenAtError(0.3), 0.0);
  LineMeasurement faint = seenAtError(0.3);
  faint.band.confidence = 0.1;
  controller.update(faint, 0.1);
  EXPECT_EQ(controller.state(), LineState::kLost);
  LineMeasurement rejected = seenAtError(0.3);
  rejected.error = "empty image";
  controller.update(rejected, 0.2);
  EXPECT_EQ(controller.state(), LineState::kLost);
}

TEST(LineController, ClockJumpingBackResets) {
  LineController controller;
  controller.update(seenAtError(0.5), 100.0);
  controller.update(unseen(), 150.0);
  EXPECT_EQ(controller.state(), LineState::kGaveUp);
  // Sim restart: time goes back; the controller starts afresh instead of computing
  // negative intervals.
  controller.update(unseen(), 1.0);
  EXPECT_EQ(controller.state(), LineState::kSearching);
}

TEST(LineController, ADenormalIntervalGivesNoDerivative) {
  LineControllerConfig config;
  config.kd = 0.0;  // an infinite error rate would give 0 * inf = NaN
  LineController controller(config);
  controller.update(seenAtError(-0.5), 0.0);
  const Twist2D twist = controller.update(seenAtError(0.5), 5e-324);
  EXPECT_DOUBLE_EQ(twist.angular, -1.5 * 0.5);
}

TEST(LineController, NeverOutputsNonFiniteValues) {
  std::mt19937 rng(3);
  const double specials[] = {kNaN, kInf, -kInf, 1e308, -1e308, 0.0, 5e-324};
  std::uniform_int_distribution<int> pick(0, 9);
  std::uniform_real_distribution<double> value(-2.0, 2.0);
  auto draw = [&] {
    const int i = pick(rng);
    return i < 7 ? specials[i] : value(rng);
  };
  for (const auto& [mode, kd] : {std::pair(ControlMode::kPD, 0.1), std::pair(ControlMode::kPD, 0.0),
                                 std::pair(ControlMode::kLecture, 0.1)}) {
    LineControllerConfig config;
    config.mode = mode;
    config.kd = kd;  // with kd = 0, an infinite error rate would make 0 * inf = NaN
    LineController controller(config);
    double stamp = 0.0;
    for (int i = 0; i < 20000; ++i) {
      LineMeasurement m = seenAtError(value(rng));
      m.band.found = pick(rng) < 8;
      m.band.error_normalised = draw();
      m.band.error_px = draw();
      m.band.confidence = draw();
      m.look_ahead = bandAt(0.0);
      m.look_ahead.error_normalised = draw();
      stamp = pick(rng) == 0 ? draw() : stamp + std::abs(value(rng)) * 1e-3;
      const Twist2D twist = controller.update(m, stamp);
      ASSERT_TRUE(std::isfinite(twist.linear) && std::isfinite(twist.angular)) << i;
    }
  }
}

TEST(LineController, ValidatesItsConfiguration) {
  auto error_for = [](auto change) {
    LineControllerConfig config;
    change(config);
    return validate(config);
  };
  EXPECT_EQ(validate(LineControllerConfig()), "");
  EXPECT_EQ(error_for([](LineControllerConfig& c) { c.kp = -1; }), "kp must be >= 0, got -1");
  EXPECT_EQ(error_for([](LineControllerConfig& c) { c.kd = kNaN; }), "kd must be >= 0, got nan");
  EXPECT_EQ(error_for([](LineControllerConfig& c) { c.max_angular = 0; }),
            "max_angular must be > 0, got 0");
  EXPECT_EQ(error_for([](LineControllerConfig& c) { c.look_ahead_weight = 1.5; }),
            "look_ahead_weight must be in [0, 1], got 1.5");
  EXPECT_EQ(error_for([](LineControllerConfig& c) { c.min_linear = 0.5; }),
            "min_linear (0.5) must be <= max_linear (0.3)");
  EXPECT_EQ(error_for([](LineControllerConfig& c) { c.search_timeout = kInf; }),
            "search_timeout must be >= 0, got inf");
  LineControllerConfig bad;
  bad.max_linear = -0.1;
  EXPECT_THROW(LineController{bad}, std::invalid_argument);
}

TEST(LineController, NamesModesAndStates) {
  EXPECT_EQ(parseControlMode("lecture"), ControlMode::kLecture);
  EXPECT_EQ(parseControlMode("pd"), ControlMode::kPD);
  EXPECT_EQ(parseControlMode("PID"), std::nullopt);
  EXPECT_STREQ(toString(ControlMode::kPD), "pd");
  EXPECT_STREQ(toString(LineState::kGaveUp), "GAVE_UP");
  EXPECT_STREQ(toString(LineState::kSearching), "SEARCHING");
}

}  // namespace
}  // namespace follow_bot
