// TagDetector on synthetic 640x480 frames (synthetic_tag.h) at known poses.
#include "follow_bot/tag_detector.h"

#include <cmath>
#include <csignal>
#include <cstdlib>

#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>
#include <gtest/gtest.h>

#include "synthetic_tag.h"

namespace follow_bot {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

CameraGeometry harnessCamera() {
  CameraGeometry camera;
  camera.pitch_rad = 0.0;
  return camera;
}

cv::Mat frameWith(const test::TagView& view, int id = 0, double size = 0.30, int black = 0,
                  int white = 255) {
  cv::Mat gray(480, 640, CV_8UC1, cv::Scalar(120));
  test::drawTag(gray, harnessCamera(), id, size, view.rotation, view.translation, black, white);
  return gray;
}

double rotationErrorDeg(const cv::Matx33d& a, const cv::Matx33d& b) {
  const double cosine = (cv::trace(a.t() * b) - 1.0) / 2.0;
  return std::acos(std::max(-1.0, std::min(1.0, cosine))) / kDeg;
}

// Tilt about the marker's vertical axis, the one the planar ambiguity flips: the angle of the
// marker's z axis in the camera's x-z plane.
double tiltDeg(const cv::Matx33d& rotation) {
  return std::atan2(rotation(0, 2), rotation(2, 2)) / kDeg;
}

struct View {
  double along, right, yaw_deg, normal_yaw_deg;
};

// Pose accuracy at 0.5-3 m. Position within 1 cm everywhere. Orientation within 1 deg wherever
// it is observable: up to 1.5 m, or at >= 15 deg incidence. Face-on beyond that a 1 deg tilt
// moves the corners by ~0.02-0.05 px, below what corner refinement resolves, so there the test
// asserts the bound the corner accuracy allows (3 deg) and, in FaceOnSweepNeverFlips, that the
// ambiguity never flips the tilt's sign from frame to frame.
class TagPose : public ::testing::TestWithParam<View> {};

TEST_P(TagPose, WithinOneCentimetreAndOneDegreeWhereObservable) {
  const View v = GetParam();
  // Marker turned by normal_yaw about its vertical axis: the camera sees it at an incidence.
  test::TagView view = test::viewFrom(v.along, v.right, v.yaw_deg * kDeg);
  const double n = v.normal_yaw_deg * kDeg;
  const cv::Matx33d turn(std::cos(n), 0, std::sin(n), 0, 1, 0, -std::sin(n), 0, std::cos(n));
  view.rotation = view.rotation * turn;
  TagDetector detector(TagDetectorConfig{});
  const std::optional<MarkerObservation> seen = detector.detect(frameWith(view), harnessCamera());
  ASSERT_TRUE(seen);
  EXPECT_EQ(seen->id, 0);
  EXPECT_LT(cv::norm(seen->translation - view.translation), 0.01);
  const double range = cv::norm(view.translation);
  const double incidence =
      std::acos(std::abs(view.translation.dot(
                    cv::Vec3d(view.rotation(0, 2), view.rotation(1, 2), view.rotation(2, 2)))) /
                range) /
      kDeg;
  const bool observable = range <= 1.5 || incidence >= 15.0;
  EXPECT_LT(rotationErrorDeg(seen->rotation, view.rotation), observable ? 1.0 : 3.0)
      << "range " << range << " incidence " << incidence;
  EXPECT_LT(seen->reprojection_error_px, 0.5);
}

INSTANTIATE_TEST_SUITE_P(Views, TagPose,
                         ::testing::Values(View{0.5, 0, 0, 0}, View{0.5, 0.05, 5, 20},
                                           View{0.8, 0.1, 0, -30}, View{1.0, 0, 0, 0},
                                           View{1.0, -0.2, -10, 45}, View{1.5, 0.2, 8, 15},
                                           View{1.5, 0, 0, -25}, View{2.0, 0, 0, 0},
                                           View{2.0, 0.4, 10, 30}, View{2.5, -0.3, -5, -40},
                                           View{3.0, 0, 0, 0}, View{3.0, 0.5, 8, 50},
                                           View{3.0, -0.6, -12, -20}));

TEST(TagDetector, SweepsNeverFlip) {
  // The planar ambiguity's two solutions are mirror tilts about the line of sight, nearly equal
  // in residual far out. Face-on beyond 1.5 m the tilt is unobservable (0.02-0.05 px per deg),
  // so there it may only stay within what corner noise allows (5 deg; 1 deg up to 1.5 m). Seen
  // at 12 deg incidence the wrong branch would read about -12 deg (24 deg off): it must never
  // be chosen, at any range; the error stays within 1 deg up to 1.5 m and 3 deg beyond (less
  // than 15 deg incidence, where tilt is still weakly observable). At 20 deg: 1 deg throughout.
  TagDetector detector(TagDetectorConfig{});
  int frames = 0;
  for (double incidence_deg : {0.0, 12.0, -20.0}) {
    for (int step = 0; step <= 25; ++step) {
      const double along = 0.5 + 0.1 * step;
      test::TagView view = test::viewFrom(along, 0.0, 0.0);
      const double n = incidence_deg * kDeg;
      view.rotation = view.rotation * cv::Matx33d(std::cos(n), 0, std::sin(n), 0, 1, 0,
                                                  -std::sin(n), 0, std::cos(n));
      const std::optional<MarkerObservation> seen =
          detector.detect(frameWith(view), harnessCamera());
      ASSERT_TRUE(seen) << along;
      ++frames;
      const double tilt_error = tiltDeg(seen->rotation) - tiltDeg(view.rotation);
      const bool observable = along <= 1.5 || std::abs(incidence_deg) >= 15.0;
      const double bound = observable ? 1.0 : incidence_deg != 0.0 ? 3.0 : 5.0;
      EXPECT_LT(std::abs(tilt_error), bound)
          << "incidence " << incidence_deg << " deg at " << along << " m";
    }
  }
  EXPECT_EQ(frames, 78);
}

TEST(TagDetector, OnlyTheConfiguredIdIsAccepted) {
  TagDetectorConfig config;
  config.id = 3;
  TagDetector detector(config);
  const test::TagView view = test::viewFrom(1.5, 0.0, 0.0);
  EXPECT_FALSE(detector.detect(frameWith(view, 0), harnessCamera()));
  const std::optional<MarkerObservation> seen =
      detector.detect(frameWith(view, 3), harnessCamera());
  ASSERT_TRUE(seen);
  EXPECT_EQ(seen->id, 3);

  // Both in one frame: the pose is the configured tag's.
  cv::Mat gray = frameWith(test::viewFrom(1.5, 0.35, 0.0), 0);
  const test::TagView right = test::viewFrom(1.5, -0.35, 0.0);
  test::drawTag(gray, harnessCamera(), 3, 0.30, right.rotation, right.translation);
  const std::optional<MarkerObservation> both = detector.detect(gray, harnessCamera());
  ASSERT_TRUE(both);
  EXPECT_NEAR(both->translation[0], right.translation[0], 0.01);
}

TEST(TagDetector, DecisionMarginGateRejectsWeakDecodes) {
  const test::TagView view = test::viewFrom(1.0, 0.0, 0.0);
  const cv::Mat faint = frameWith(view, 0, 0.30, 110, 135);  // 25 grey levels of contrast
  TagDetectorConfig config;
  config.min_decision_margin = 0;
  const std::optional<MarkerObservation> seen = TagDetector(config).detect(faint, harnessCamera());
  ASSERT_TRUE(seen);
  EXPECT_LT(seen->quality, 30.0);
  EXPECT_FALSE(TagDetector(TagDetectorConfig{}).detect(faint, harnessCamera()));
  const std::optional<MarkerObservation> crisp =
      TagDetector(TagDetectorConfig{}).detect(frameWith(view), harnessCamera());
  ASSERT_TRUE(crisp);
  EXPECT_GT(crisp->quality, 100.0);
}

TEST(TagDetector, CornersAreTopLeftFirstClockwise) {
  const test::TagView view = test::viewFrom(1.0, 0.0, 0.0);
  const std::optional<MarkerObservation> seen =
      TagDetector(TagDetectorConfig{}).detect(frameWith(view), harnessCamera());
  ASSERT_TRUE(seen);
  EXPECT_LT(seen->corners[0].x, seen->corners[1].x);  // TL left of TR
  EXPECT_LT(seen->corners[1].y, seen->corners[2].y);  // TR above BR
  EXPECT_GT(seen->corners[2].x, seen->corners[3].x);  // BR right of BL
}

// Corners in OpenCV's pixel convention (centres at integers, as the intrinsics): libapriltag's
// own sit +0.5 px in x and y, which alone moved the pose 1-4 mm at 0.5-3 m (now: -0.09 px).
TEST(TagDetector, CornersHaveNoHalfPixelBias) {
  const double h = 0.15;
  const cv::Vec3d object[4] = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};  // TL, TR, BR, BL
  const CameraGeometry camera = harnessCamera();
  TagDetector detector(TagDetectorConfig{});
  cv::Point2d bias(0, 0);
  int corners = 0;
  for (const double along : {0.6, 1.0, 2.0, 3.0}) {
    const test::TagView view = test::viewFrom(along, 0.1 * along, 0.0);
    const std::optional<MarkerObservation> seen = detector.detect(frameWith(view), camera);
    ASSERT_TRUE(seen) << along;
    for (int i = 0; i < 4; ++i, ++corners) {
      const cv::Vec3d p = view.rotation * object[i] + view.translation;
      bias += seen->corners[i] -
              cv::Point2d(camera.fx * p[0] / p[2] + camera.cx, camera.fy * p[1] / p[2] + camera.cy);
    }
  }
  EXPECT_LT(std::abs(bias.x / corners), 0.2) << bias.x / corners;
  EXPECT_LT(std::abs(bias.y / corners), 0.2) << bias.y / corners;
}

TEST(TagDetector, BadInputGivesNothing) {
  TagDetector detector(TagDetectorConfig{});
  EXPECT_FALSE(detector.detect(cv::Mat(), harnessCamera()));
  EXPECT_FALSE(detector.detect(cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(0)), harnessCamera()));
  CameraGeometry zero = harnessCamera();
  zero.fx = zero.fy = 0.0;
  EXPECT_FALSE(detector.detect(frameWith(test::viewFrom(1.0, 0, 0)), zero));
}

TEST(TagDetector, QuadSearchSizeFollowsLibapriltagsDecimation) {
  EXPECT_EQ(quadSearchSize({640, 480}, 1.0), cv::Size(640, 480));
  EXPECT_EQ(quadSearchSize({640, 480}, 2.0), cv::Size(320, 240));
  EXPECT_EQ(quadSearchSize({640, 5}, 2.0), cv::Size(320, 3));
  EXPECT_EQ(quadSearchSize({640, 4}, 2.0), cv::Size(320, 2));
  EXPECT_EQ(quadSearchSize({640, 4}, 2.5), cv::Size(320, 2));  // the integer part
  EXPECT_EQ(quadSearchSize({8, 6}, 1.5), cv::Size(4, 4));
  EXPECT_EQ(quadSearchSize({2, 5}, 1.5), cv::Size(0, 2));
  EXPECT_EQ(quadSearchSize({640, 17}, 8.0), cv::Size(80, 3));
}

// Runs libapriltag itself (quad_decimate 2) on a mid-grey frame of this size.
void detectWithLibapriltag(int cols, int rows) {
  cv::Mat gray(rows, cols, CV_8UC1, cv::Scalar(128));
  apriltag_family_t* family = tag36h11_create();
  apriltag_detector_t* detector = apriltag_detector_create();
  apriltag_detector_add_family_bits(detector, family, 0);
  detector->quad_decimate = 2.0f;
  image_u8_t image{gray.cols, gray.rows, static_cast<int32_t>(gray.step[0]), gray.data};
  apriltag_detections_destroy(apriltag_detector_detect(detector, &image));
  apriltag_detector_destroy(detector);
  tag36h11_destroy(family);
}

// The library's limit (apriltag 3.3): 3 quad-search rows work, 2 crash it. If a newer
// libapriltag survives 2, kMinQuadSearchRows can go.
TEST(TagDetectorDeathTest, LibapriltagCrashesOnTwoQuadSearchRows) {
  detectWithLibapriltag(640, 5);  // 3 rows: fine
  EXPECT_EXIT((detectWithLibapriltag(640, 4), std::exit(0)), ::testing::KilledBySignal(SIGSEGV),
              "");
}

// Every size around the limit, for every decimation: no crash, and nothing found below it.
TEST(TagDetector, TinyFramesAtTheQuadSearchLimitGiveNothingAndNoCrash) {
  for (const double decimate : {1.0, 1.5, 2.0, 2.5, 3.0, 8.0}) {
    TagDetectorConfig config;
    config.quad_decimate = decimate;
    TagDetector detector(config);
    for (int rows = 1; rows <= 26; ++rows) {
      for (const int cols : {1, 2, 3, 4, 66, 640}) {
        const cv::Mat gray(rows, cols, CV_8UC1, cv::Scalar(128));
        EXPECT_FALSE(detector.detect(gray, harnessCamera())) << cols << "x" << rows;
      }
    }
  }
}

TEST(TagDetector, RejectsBadConfig) {
  TagDetectorConfig config;
  config.size_m = 0.0;
  EXPECT_THROW(TagDetector{config}, std::invalid_argument);
  config = TagDetectorConfig{};
  config.family = "tag99h1";
  EXPECT_THROW(TagDetector{config}, std::invalid_argument);
  config = TagDetectorConfig{};
  config.id = 587;
  EXPECT_THROW(TagDetector{config}, std::invalid_argument);
}

}  // namespace
}  // namespace follow_bot
