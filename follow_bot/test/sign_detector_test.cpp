#include "follow_bot/sign_detector.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "synthetic_sign.h"

namespace follow_bot {
namespace {

using test::angleBetween;
using test::kSignWidthM;
using test::renderSign;
using test::rotationX;
using test::rotationY;

constexpr double kPi = 3.14159265358979323846;
constexpr int kWidth = test::kSignFrameWidth;
constexpr int kHeight = test::kSignFrameHeight;

double deg(double rad) { return rad * 180.0 / kPi; }
double rad(double deg) { return deg * kPi / 180.0; }

// Pinhole intrinsics of the harness camera (640x480, 60 deg HFOV); the rest is unused here.
CameraGeometry harnessCamera() { return CameraGeometry{}; }

class SignDetectorTest : public ::testing::Test {
 protected:
  static SignDetectorConfig config() {
    SignDetectorConfig c;
    c.image_path = PARKING_SIGN_IMAGE;
    c.width_m = kSignWidthM;
    return c;
  }
  const cv::Mat reference_ = cv::imread(PARKING_SIGN_IMAGE, cv::IMREAD_GRAYSCALE);
  const CameraGeometry camera_ = harnessCamera();
};

struct View {
  double range_m;    // distance of the sign centre along the optical axis
  double lateral_m;  // sign centre right of the optical axis
  double yaw_deg;    // sign turned about its vertical axis (0 = face-on to the optical axis)
  double pitch_deg;  // sign tilted about its horizontal axis
};

// Range 0.5-3 m, face-on and turned up to 50 deg, off-centre, tilted.
const std::vector<View> kViews = {
    {0.5, 0.0, 0.0, 0.0},  {0.5, 0.05, 35.0, 0.0}, {0.5, -0.05, -45.0, 5.0},
    {1.0, 0.0, 0.0, 0.0},  {1.0, 0.2, 30.0, 0.0},  {1.0, -0.2, -50.0, -5.0},
    {1.5, 0.0, 0.0, 0.0},  {1.5, 0.3, 20.0, 10.0}, {1.5, -0.4, -40.0, 0.0},
    {2.0, 0.0, 0.0, 0.0},  {2.0, 0.5, 45.0, 0.0},  {2.0, -0.3, -30.0, -8.0},
    {2.5, 0.0, 0.0, 0.0},  {2.5, 0.6, 30.0, 0.0},  {2.5, -0.6, -45.0, 0.0},
    {3.0, 0.0, 0.0, 0.0},  {3.0, 0.5, 30.0, 0.0},  {3.0, -0.8, -45.0, 5.0},
    {3.0, 0.0, 10.0, 0.0},
};

// Edge displacement below which a tilt goes unseen: the aligned sign's outline is good to about
// this (measured 0.05-0.15 px); the tag pose test allows the same 0.1 px.
constexpr double kHiddenPx = 0.1;

// The rotation error (degrees) a pose of the sign at `rotation`, `translation` may have: 1 deg,
// except seen face-on from afar, where a tilt t moves the sign's edges by only
// fx (w/2)^2 t / range^2 pixels (0.04 px per degree at 3 m for the 0.4 m sign) and a tilt that
// kHiddenPx of edge error can hide is unobservable.
double observableBoundDeg(const CameraGeometry& camera, const cv::Matx33d& rotation,
                          const cv::Vec3d& translation) {
  const double range = translation[2];
  const double incidence = deg(std::acos(std::abs(rotation(2, 2))));
  if (range <= 1.05 || incidence >= 15.0) return 1.0;
  return 1.0 + deg(kHiddenPx * range * range / (camera.fx * std::pow(kSignWidthM / 2, 2)));
}

TEST_F(SignDetectorTest, PoseOfRenderedViewsWithinOneCentimetreAndOneDegree) {
  for (const View& view : kViews) {
    SignDetector detector(config());
    const cv::Matx33d rotation = rotationY(rad(view.yaw_deg)) * rotationX(rad(view.pitch_deg));
    const cv::Vec3d translation(view.lateral_m, 0.0, view.range_m);
    const cv::Mat frame = renderSign(reference_, camera_, rotation, translation, 2.0);
    const auto seen = detector.detect(frame, camera_);
    ASSERT_TRUE(seen) << view.range_m << " m, " << view.yaw_deg << " deg";
    const double position_error = cv::norm(seen->translation - translation);
    const double angle_error = deg(angleBetween(seen->rotation, rotation));
    std::printf(
        "range %.1f lateral %+.2f yaw %+5.1f pitch %+4.1f: %3.0f inliers, position %.4f m,"
        " angle %.3f deg, rms %.2f px\n",
        view.range_m, view.lateral_m, view.yaw_deg, view.pitch_deg, seen->quality, position_error,
        angle_error, seen->reprojection_error_px);
    EXPECT_LT(position_error, 0.01) << view.range_m << " m, " << view.yaw_deg << " deg";
    EXPECT_LT(angle_error, observableBoundDeg(camera_, rotation, translation))
        << view.range_m << " m, " << view.yaw_deg << " deg";
    // Corners TL, TR, BR, BL go clockwise on screen.
    EXPECT_LT(seen->corners[0].x, seen->corners[1].x);
    EXPECT_LT(seen->corners[1].y, seen->corners[2].y);
    EXPECT_EQ(seen->id, 0);
  }
}

// The other solution of the planar pose's two-fold ambiguity for a sign seen at `rotation`,
// `translation`: IPPE on the exact projection of its corners.
cv::Matx33d mirrorPose(const cv::Mat& reference, const CameraGeometry& camera,
                       const cv::Matx33d& rotation, const cv::Vec3d& translation) {
  const float w = static_cast<float>(kSignWidthM / 2);
  const float h = w * reference.rows / reference.cols;
  const std::vector<cv::Point3f> corners = {{-w, -h, 0}, {w, -h, 0}, {w, h, 0}, {-w, h, 0}};
  const cv::Matx33d k(camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0);
  cv::Vec3d rvec;
  cv::Rodrigues(rotation, rvec);
  std::vector<cv::Point2f> image;
  cv::projectPoints(corners, rvec, translation, k, cv::noArray(), image);
  std::vector<cv::Mat> rvecs, tvecs;
  cv::solvePnPGeneric(corners, image, k, cv::noArray(), rvecs, tvecs, false, cv::SOLVEPNP_IPPE);
  cv::Matx33d farthest = rotation;
  for (const cv::Mat& solution : rvecs) {
    cv::Matx33d candidate;
    cv::Rodrigues(solution, candidate);
    if (angleBetween(candidate, rotation) > angleBetween(farthest, rotation)) farthest = candidate;
  }
  return farthest;
}

// A sweep of face-on views across the field at 2-3 m: the line of sight meets the sign up to
// 17 deg off its normal, where the planar pose's mirror solution is ~2x that away. Every frame
// (tracked with one detector, as a node would) must stay on the true solution, nearer the true
// pose than its mirror, and within the observable bound of its range or 0.5 deg of a fresh
// search's angle, whichever is larger. When the alignment solved in floats, a tracked frame kept
// most of the last frame's tilt and was 3.6 deg off at 3 m with some CPUs' SIMD kernels.
// tests/accuracy/test_sign_sweep_cpus.py runs this under four instruction sets and compares
// the lines.
TEST_F(SignDetectorTest, NoFlipsOverAFrontoParallelSweep) {
  SignDetector detector(config());
  int frames = 0;
  for (double range : {3.0, 2.5, 2.0}) {
    for (double lateral = -0.7; lateral <= 0.7 + 1e-9; lateral += 0.1) {
      const cv::Matx33d rotation = cv::Matx33d::eye();
      const cv::Vec3d translation(lateral, 0.1, range);
      const cv::Mat frame = renderSign(reference_, camera_, rotation, translation, 2.0);
      const auto seen = detector.detect(frame, camera_);
      ASSERT_TRUE(seen) << range << " m, lateral " << lateral;
      const auto searched = SignDetector(config()).detect(frame, camera_);
      ASSERT_TRUE(searched) << range << " m, lateral " << lateral;
      const double error = deg(angleBetween(seen->rotation, rotation));
      const double searched_error = deg(angleBetween(searched->rotation, rotation));
      const double bound = observableBoundDeg(camera_, rotation, translation);
      const cv::Matx33d mirror = mirrorPose(reference_, camera_, rotation, translation);
      std::printf(
          "range %.1f lateral %+.1f %s: angle %.3f deg, searched %.3f, bound %.2f, "
          "mirror %.2f away\n",
          range, lateral, detector.lastTracked() ? "tracked " : "searched", error, searched_error,
          bound, deg(angleBetween(mirror, rotation)));
      EXPECT_LT(angleBetween(seen->rotation, rotation), angleBetween(seen->rotation, mirror))
          << range << " m, lateral " << lateral << ": nearer the mirror, "
          << deg(angleBetween(mirror, rotation)) << " deg from the truth";
      EXPECT_LT(error, std::max(bound, searched_error + 0.5)) << range << " m, lateral " << lateral;
      EXPECT_LT(cv::norm(seen->translation - translation), 0.01) << range << " m, " << lateral;
      ++frames;
    }
  }
  EXPECT_EQ(frames, 45);
}

// A sign moving ~10 px and turning a little per frame: every frame after the first is tracked,
// and its pose stays within the accuracy bounds (1 cm; the angle of a fresh detector's plus
// 0.5 deg, which covers the face-on far tilt that neither observes).
TEST_F(SignDetectorTest, TracksAMovingSignAsAccuratelyAsSearching) {
  SignDetector tracking(config());
  for (int i = 0; i < 20; ++i) {
    const cv::Matx33d rotation = rotationY(rad(20.0 - 1.5 * i));
    const cv::Vec3d translation(-0.3 + 0.03 * i, 0.02, 2.0 - 0.05 * i);
    const cv::Mat frame = renderSign(reference_, camera_, rotation, translation, 2.0, i + 1);
    const auto seen = tracking.detect(frame, camera_);
    ASSERT_TRUE(seen) << i;
    EXPECT_EQ(tracking.lastTracked(), i > 0) << i;
    SignDetector searching(config());
    const auto searched = searching.detect(frame, camera_);
    ASSERT_TRUE(searched) << i;
    EXPECT_FALSE(searching.lastTracked());
    EXPECT_LT(cv::norm(seen->translation - translation), 0.01) << i;
    EXPECT_LT(deg(angleBetween(seen->rotation, rotation)),
              deg(angleBetween(searched->rotation, rotation)) + 0.5)
        << i;
  }
}

TEST_F(SignDetectorTest, SearchesAgainAfterTheSignDisappearsOrJumps) {
  SignDetector detector(config());
  const cv::Vec3d left(-0.3, 0.0, 1.5), right(0.35, 0.0, 1.5);
  const cv::Matx33d face_on = cv::Matx33d::eye();
  ASSERT_TRUE(detector.detect(renderSign(reference_, camera_, face_on, left, 2.0, 1), camera_));
  ASSERT_TRUE(detector.detect(renderSign(reference_, camera_, face_on, left, 2.0, 2), camera_));
  EXPECT_TRUE(detector.lastTracked());
  // Gone: nothing, then found again by the search.
  EXPECT_FALSE(detector.detect(cv::Mat(kHeight, kWidth, CV_8UC1, cv::Scalar(128)), camera_));
  EXPECT_FALSE(detector.lastTracked());
  auto seen = detector.detect(renderSign(reference_, camera_, face_on, left, 2.0, 3), camera_);
  ASSERT_TRUE(seen);
  EXPECT_FALSE(detector.lastTracked());
  EXPECT_LT(cv::norm(seen->translation - left), 0.01);
  // Jumped further than tracking reaches: found by the search, where it now is.
  seen = detector.detect(renderSign(reference_, camera_, face_on, right, 2.0, 4), camera_);
  ASSERT_TRUE(seen);
  EXPECT_FALSE(detector.lastTracked());
  EXPECT_LT(cv::norm(seen->translation - right), 0.01);
  seen = detector.detect(renderSign(reference_, camera_, face_on, right, 2.0, 5), camera_);
  ASSERT_TRUE(seen);
  EXPECT_TRUE(detector.lastTracked());
}

TEST_F(SignDetectorTest, AFrameOfAnotherSizeStartsAfresh) {
  SignDetector detector(config());
  const cv::Vec3d ahead(0.0, 0.0, 1.5);
  ASSERT_TRUE(detector.detect(renderSign(reference_, camera_, cv::Matx33d::eye(), ahead), camera_));
  const cv::Mat larger =
      renderSign(reference_, camera_, cv::Matx33d::eye(), ahead, 0.0, 1, cv::Size(800, 600));
  ASSERT_TRUE(detector.detect(larger, camera_));
  EXPECT_FALSE(detector.lastTracked());
  ASSERT_TRUE(detector.detect(larger, camera_));
  EXPECT_TRUE(detector.lastTracked());
}

TEST_F(SignDetectorTest, NothingInBlankOrNoiseImages) {
  SignDetector detector(config());
  EXPECT_FALSE(detector.detect(cv::Mat(kHeight, kWidth, CV_8UC1, cv::Scalar(128)), camera_));
  cv::Mat noise(kHeight, kWidth, CV_8UC1);
  cv::RNG rng(7);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  EXPECT_FALSE(detector.detect(noise, camera_));
  EXPECT_FALSE(detector.detect(cv::Mat(), camera_));
  // Only mono8 is accepted; colour must be converted by the caller.
  EXPECT_FALSE(detector.detect(cv::Mat(kHeight, kWidth, CV_8UC3, cv::Scalar(0, 0, 0)), camera_));
}

TEST_F(SignDetectorTest, MirroredSignIsRejected) {
  SignDetector detector(config());
  cv::Mat frame = renderSign(reference_, camera_, cv::Matx33d::eye(), {0.0, 0.0, 1.0});
  cv::flip(frame, frame, 1);
  EXPECT_FALSE(detector.detect(frame, camera_));
}

std::string expectThrow(const SignDetectorConfig& config) {
  try {
    SignDetector detector(config);
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "no exception";
}

TEST_F(SignDetectorTest, StartupErrors) {
  SignDetectorConfig missing = config();
  missing.image_path = "/nonexistent/parking_sign.png";
  EXPECT_NE(expectThrow(missing).find("cannot read the sign image"), std::string::npos);

  const std::string text_path = testing::TempDir() + "sign_not_an_image.png";
  std::ofstream(text_path) << "not a PNG";
  SignDetectorConfig text = config();
  text.image_path = text_path;
  EXPECT_NE(expectThrow(text).find("cannot read the sign image"), std::string::npos);

  const std::string blank_path = testing::TempDir() + "sign_blank.png";
  ASSERT_TRUE(cv::imwrite(blank_path, cv::Mat(300, 400, CV_8UC1, cv::Scalar(200))));
  SignDetectorConfig blank = config();
  blank.image_path = blank_path;
  EXPECT_NE(expectThrow(blank).find("featureless"), std::string::npos) << expectThrow(blank);

  for (double width : {0.0, -0.4, std::nan("")}) {
    SignDetectorConfig bad = config();
    bad.width_m = width;
    EXPECT_NE(expectThrow(bad).find("width_m must be > 0"), std::string::npos) << width;
  }
  SignDetectorConfig no_path = config();
  no_path.image_path.clear();
  EXPECT_NE(expectThrow(no_path).find("image_path"), std::string::npos);
  SignDetectorConfig bad_ratio = config();
  bad_ratio.ratio = 1.5;
  EXPECT_NE(expectThrow(bad_ratio).find("ratio must be in"), std::string::npos);
  SignDetectorConfig few_inliers = config();
  few_inliers.min_inliers = 3;
  EXPECT_NE(expectThrow(few_inliers).find("min_inliers must be >= 4"), std::string::npos);
  // Only the alignment vouches for a tracked homography: a tracked frame is always aligned.
  SignDetectorConfig unaligned_tracking = config();
  unaligned_tracking.track_refine_passes = 0;
  EXPECT_NE(expectThrow(unaligned_tracking).find("track_refine_passes must be >= 1"),
            std::string::npos);
  SignDetectorConfig no_track_iterations = config();
  no_track_iterations.track_refine_iterations = 0;
  EXPECT_NE(expectThrow(no_track_iterations).find("track_refine_iterations must be >= 1"),
            std::string::npos);
  SignDetectorConfig far_motion = config();
  far_motion.max_track_motion_px = 0.0;
  EXPECT_NE(expectThrow(far_motion).find("max_track_motion_px must be > 0"), std::string::npos);

  EXPECT_GE(SignDetector(config()).referenceFeatures(), config().min_reference_features);
}

}  // namespace
}  // namespace follow_bot
