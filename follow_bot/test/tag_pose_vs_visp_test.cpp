// TagDetector's pose against ViSP 3.5's vpDetectorAprilTag (its best estimator for one tag,
// HOMOGRAPHY_ORTHOGONAL_ITERATION, or its default HOMOGRAPHY_VIRTUAL_VS) on the same frames: tags
// rendered at known poses as a camera would see them (anti-aliased, a lens blur, sensor noise,
// 8-bit quantisation, print contrast rather than pure black and white). Both read libapriltag's
// corners; ViSP 3.5 takes them in apriltag's half-pixel-centred coordinates against integer-centred
// intrinsics (a 0.5 px shift in x and y), TagDetector shifts them first, hence its lead.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include <gtest/gtest.h>
#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpImage.h>
#include <visp3/detection/vpDetectorAprilTag.h>

#include "follow_bot/tag_detector.h"
#include "synthetic_tag.h"

namespace follow_bot {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kTagSize = 0.30;
constexpr int kSeeds = 4;             // noise draws per view
constexpr double kBlurSigmaPx = 0.8;  // the lens' point spread
constexpr double kNoiseSigma = 2.0;   // grey levels
constexpr double kMarginMm = 0.2;     // ours vs ViSP, mean translation error over the views
constexpr double kMarginDeg = 0.1;    // ours vs ViSP, mean rotation error over the views
constexpr double kMeanBoundMm = 1.2;  // ours, absolute (measured 0.8 mm; ViSP 2.6-2.8 mm)

struct View {
  double along, right, incidence_deg;
};

struct Errors {
  double translation_mm = 0;
  double rotation_deg = 0;
};

cv::Mat cameraFrame(const CameraGeometry& camera, const test::TagView& view, int seed) {
  cv::Mat gray(480, 640, CV_8UC1, cv::Scalar(120));
  cv::rectangle(gray, cv::Rect(0, 300, 640, 180), cv::Scalar(95), cv::FILLED);
  test::drawTag(gray, camera, 0, kTagSize, view.rotation, view.translation, 25, 215);
  cv::Mat blurred;
  gray.convertTo(blurred, CV_32F);
  cv::GaussianBlur(blurred, blurred, cv::Size(), kBlurSigmaPx);
  cv::Mat noise(gray.size(), CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0, kNoiseSigma);
  blurred += noise;
  blurred.convertTo(gray, CV_8UC1);  // rounds and saturates, as the sensor's ADC
  return gray;
}

double rotationErrorDeg(const cv::Matx33d& a, const cv::Matx33d& b) {
  const double cosine = (cv::trace(a.t() * b) - 1.0) / 2.0;
  return std::acos(std::max(-1.0, std::min(1.0, cosine))) / kDeg;
}

Errors errorsOf(const cv::Matx33d& rotation, const cv::Vec3d& translation,
                const test::TagView& truth) {
  return {1000.0 * cv::norm(translation - truth.translation),
          rotationErrorDeg(rotation, truth.rotation)};
}

// ViSP's pose of the one tag in `frame`, in our marker frame (x right, y down, z into the tag).
std::optional<Errors> vispErrors(vpDetectorAprilTag& visp, const cv::Mat& frame,
                                 const CameraGeometry& camera, const test::TagView& truth) {
  vpImage<unsigned char> image(frame.rows, frame.cols);
  std::copy(frame.datastart, frame.dataend, image.bitmap);
  const vpCameraParameters intrinsics(camera.fx, camera.fy, camera.cx, camera.cy);
  std::vector<vpHomogeneousMatrix> poses;
  if (!visp.detect(image, kTagSize, intrinsics, poses) || poses.size() != 1) return std::nullopt;
  cv::Matx33d rotation;
  cv::Vec3d translation;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) rotation(r, c) = poses[0][r][c];
    translation[r] = poses[0][r][3];
  }
  return errorsOf(rotation, translation, truth);
}

class TagPoseVsVisp : public ::testing::TestWithParam<vpDetectorAprilTag::vpPoseEstimationMethod> {
};

TEST_P(TagPoseVsVisp, TranslationNoWorseThanVisp) {
  CameraGeometry camera;
  camera.pitch_rad = 0.0;
  const std::vector<View> views = {
      {0.5, 0.0, 0},  {0.5, 0.05, 30}, {0.8, 0.1, -45}, {1.0, 0.0, 0},  {1.0, -0.2, 20},
      {1.5, 0.2, 40}, {1.5, 0.0, -15}, {2.0, 0.0, 0},   {2.0, 0.4, 30}, {2.5, -0.3, -40},
      {3.0, 0.0, 0},  {3.0, 0.5, 45},  {3.0, -0.6, -20}};
  TagDetectorConfig config;
  TagDetector ours(config);
  vpDetectorAprilTag visp(vpDetectorAprilTag::TAG_36h11, GetParam());
  visp.setAprilTagNbThreads(1);
  visp.setAprilTagQuadDecimate(static_cast<float>(config.quad_decimate));
  visp.setZAlignedWithCameraAxis(true);  // our marker frame: x right, y down, z into the tag

  Errors ours_sum, visp_sum;
  std::printf("  view (m, m, deg)     ours mm / deg     ViSP mm / deg\n");
  for (const View& v : views) {
    test::TagView truth = test::viewFrom(v.along, v.right, 0.0);
    const double n = v.incidence_deg * kDeg;
    truth.rotation = truth.rotation * cv::Matx33d(std::cos(n), 0, std::sin(n), 0, 1, 0,
                                                  -std::sin(n), 0, std::cos(n));
    Errors ours_view, visp_view;
    for (int seed = 0; seed < kSeeds; ++seed) {
      const cv::Mat frame = cameraFrame(camera, truth, seed);
      ours.reset();  // no previous pose to lean on
      const std::optional<MarkerObservation> seen = ours.detect(frame, camera);
      const std::optional<Errors> theirs = vispErrors(visp, frame, camera, truth);
      ASSERT_TRUE(seen && theirs) << v.along << " m, seed " << seed;
      const Errors mine = errorsOf(seen->rotation, seen->translation, truth);
      EXPECT_LT(mine.translation_mm, 5.0 * v.along) << v.along << " m, seed " << seed;
      ours_view.translation_mm += mine.translation_mm / kSeeds;
      ours_view.rotation_deg += mine.rotation_deg / kSeeds;
      visp_view.translation_mm += theirs->translation_mm / kSeeds;
      visp_view.rotation_deg += theirs->rotation_deg / kSeeds;
    }
    std::printf("  %.1f %+.2f %+3.0f        %6.2f / %5.2f     %6.2f / %5.2f\n", v.along, v.right,
                v.incidence_deg, ours_view.translation_mm, ours_view.rotation_deg,
                visp_view.translation_mm, visp_view.rotation_deg);
    ours_sum.translation_mm += ours_view.translation_mm / views.size();
    ours_sum.rotation_deg += ours_view.rotation_deg / views.size();
    visp_sum.translation_mm += visp_view.translation_mm / views.size();
    visp_sum.rotation_deg += visp_view.rotation_deg / views.size();
  }
  std::printf("  mean                 %6.2f / %5.2f     %6.2f / %5.2f\n", ours_sum.translation_mm,
              ours_sum.rotation_deg, visp_sum.translation_mm, visp_sum.rotation_deg);
  // Ours may trail ViSP's mean by kMarginMm (noise draws differ in which estimator they favour)
  // and must hold 0.5 % of the range in every view.
  EXPECT_LE(ours_sum.translation_mm, visp_sum.translation_mm + kMarginMm);
  EXPECT_LT(ours_sum.rotation_deg, visp_sum.rotation_deg + kMarginDeg);
  EXPECT_LT(ours_sum.translation_mm, kMeanBoundMm);
}

INSTANTIATE_TEST_SUITE_P(Methods, TagPoseVsVisp,
                         ::testing::Values(vpDetectorAprilTag::HOMOGRAPHY_VIRTUAL_VS,
                                           vpDetectorAprilTag::HOMOGRAPHY_ORTHOGONAL_ITERATION));

}  // namespace
}  // namespace follow_bot
