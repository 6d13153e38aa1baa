#include "image_converter/stitching.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "synthetic_views.h"

namespace image_converter {
namespace {

using testing::cylinderView;
using testing::texturedScene;

constexpr double kPi = 3.141592653589793;

// Two views cut from one scene: A is a crop, B a rotated, slightly perspective view further
// right, overlapping A by about 40 % of its width.
struct TwoViews {
  cv::Mat scene, a, b;
  cv::Point a_offset{20, 30};  // A's pixel (0, 0) in the scene
  cv::Matx33d b_to_scene, b_to_a;
};

TwoViews makeTwoViews() {
  TwoViews views;
  views.scene = texturedScene(cv::Size(900, 560), 7);
  views.a = views.scene(cv::Rect(views.a_offset, cv::Size(500, 480))).clone();
  const double angle = 4.0 * kPi / 180.0, c = std::cos(angle), s = std::sin(angle);
  const cv::Matx33d about_centre = cv::Matx33d(1, 0, 240, 0, 1, 240, 0, 0, 1) *
                                   cv::Matx33d(c, -s, 0, s, c, 0, 0, 0, 1) *
                                   cv::Matx33d(1, 0, -240, 0, 1, -240, 0, 0, 1);
  const cv::Matx33d perspective(1, 0, 0, 0, 1, 0, 2e-5, -1e-5, 1);
  views.b_to_scene = cv::Matx33d(1, 0, 330, 0, 1, 40, 0, 0, 1) * about_centre * perspective;
  cv::warpPerspective(views.scene, views.b, views.b_to_scene, cv::Size(480, 480),
                      cv::INTER_LINEAR | cv::WARP_INVERSE_MAP);
  views.b_to_a =
      cv::Matx33d(1, 0, -views.a_offset.x, 0, 1, -views.a_offset.y, 0, 0, 1) * views.b_to_scene;
  return views;
}

double largestCornerError(const cv::Matx33d& estimate, const cv::Matx33d& truth,
                          const cv::Size& size) {
  double largest = 0.0;
  for (const cv::Point2d& corner :
       {cv::Point2d(0, 0), cv::Point2d(size.width, 0), cv::Point2d(size.width, size.height),
        cv::Point2d(0, size.height)}) {
    largest = std::max(
        largest, cv::norm(applyHomography(estimate, corner) - applyHomography(truth, corner)));
  }
  return largest;
}

// The two views, and the default match options with the detector under test.
class TwoViewTest : public ::testing::TestWithParam<Detector> {
 protected:
  void SetUp() override { options.detector = GetParam(); }

  const TwoViews views = makeTwoViews();
  MatchOptions options;
};

TEST_P(TwoViewTest, RecoversTheHomographyWithinOnePixelAtEveryCorner) {
  const PairMatch match = matchPair(views.a, views.b, options);
  ASSERT_TRUE(match.ok()) << match.error;
  const double error = largestCornerError(match.homography, views.b_to_a, views.b.size());
  RecordProperty("largest_corner_error_px", std::to_string(error));
  std::printf(
      "[%s] inliers %d of %d matches, RMS reprojection %.3f px, corner error %.3f px, ECC %s\n",
      detectorName(GetParam()).c_str(), match.inliers, match.matches, match.reprojection_error_px,
      error, match.refined ? "kept" : "not used");
  EXPECT_LT(error, 1.0);
  EXPECT_GE(match.inliers, options.min_inliers);
  EXPECT_LT(match.reprojection_error_px, options.ransac_threshold_px);
}

// Mean absolute difference (grey levels, over the 3 channels) between `image` and the scene
// over the pixels where both views are valid (2 px inside either border), with `to_scene`
// mapping image pixels to scene pixels.
double overlapMad(const cv::Mat& image, const cv::Point2d& a_origin, const TwoViews& views) {
  const cv::Matx33d a_to_b = views.b_to_a.inv();
  const cv::Rect2d a_inner(2, 2, views.a.cols - 4, views.a.rows - 4);
  const cv::Rect2d b_inner(2, 2, views.b.cols - 4, views.b.rows - 4);
  double sum = 0.0;
  int count = 0;
  for (int row = 0; row < image.rows; ++row) {
    for (int col = 0; col < image.cols; ++col) {
      const cv::Point2d in_a = cv::Point2d(col, row) - a_origin;
      if (!a_inner.contains(in_a) || !b_inner.contains(applyHomography(a_to_b, in_a))) continue;
      const cv::Point scene_pixel = cv::Point(cvRound(in_a.x), cvRound(in_a.y)) + views.a_offset;
      const cv::Vec3b& got = image.at<cv::Vec3b>(row, col);
      const cv::Vec3b want = views.scene.at<cv::Vec3b>(scene_pixel);
      for (int ch = 0; ch < 3; ++ch) sum += std::abs(got[ch] - want[ch]);
      count += 3;
    }
  }
  return count > 0 ? sum / count : 1e9;
}

TEST_P(TwoViewTest, StitchMatchesTheSceneInTheOverlapAsWellAsResamplingAllows) {
  const StitchResult stitched = stitchPair(views.a, views.b, options);
  ASSERT_TRUE(stitched.ok()) << stitched.error;
  // B lies right of A, a little above it (rotated): A lands at column 0, an integer row.
  EXPECT_EQ(stitched.origin_of_first.x, 0.0);
  EXPECT_EQ(stitched.origin_of_first.y, std::round(stitched.origin_of_first.y));

  // The bound: B went through two bilinear resamplings (scene -> B -> panorama). Doing exactly
  // that with the true homography gives the error no stitch can beat for B's pixels; the blend
  // averages B with A's exact pixels, so the stitch must stay below that, plus 0.5 grey level
  // for the estimated homography's sub-pixel error.
  cv::Mat b_resampled(views.a.size(), CV_8UC3, cv::Scalar::all(0));
  cv::warpPerspective(views.b, b_resampled, views.b_to_a, views.a.size());
  const double resampling_mad = overlapMad(b_resampled, cv::Point2d(0, 0), views);
  const double stitch_mad = overlapMad(stitched.panorama, stitched.origin_of_first, views);
  std::printf("[%s] overlap MAD %.3f grey levels (B resampled twice: %.3f)\n",
              detectorName(GetParam()).c_str(), stitch_mad, resampling_mad);
  EXPECT_LT(stitch_mad, resampling_mad + 0.5);
  EXPECT_LT(stitch_mad, 3.0);
  EXPECT_GT(stitched.panorama.cols, views.a.cols + 250);
}

INSTANTIATE_TEST_SUITE_P(Detectors, TwoViewTest, ::testing::Values(Detector::kOrb, Detector::kSift),
                         [](const auto& info) { return detectorName(info.param); });

// Views of a camera turning right in place, left to right, overlapping by two thirds.
struct TurnSequence {
  double f = 320.0 / std::tan(30.0 * kPi / 180.0);  // 640 px wide, 60 deg field of view
  cv::Size view_size{640, 480};
  std::vector<double> yaws{30.0 * kPi / 180.0, 10.0 * kPi / 180.0, -10.0 * kPi / 180.0,
                           -30.0 * kPi / 180.0};
  std::vector<cv::Mat> views;
  // A cylindrical panorama spans f * (yaw span + horizontal field of view) pixels.
  double expectedWidth() const {
    return f * (yaws.front() - yaws.back() + 2.0 * std::atan(view_size.width / (2.0 * f)));
  }
};

TurnSequence makeTurnSequence() {
  TurnSequence sequence;
  const cv::Mat cylinder = texturedScene(cv::Size(1500, 700), 11);
  for (double yaw : sequence.yaws) {
    sequence.views.push_back(cylinderView(cylinder, sequence.f, sequence.view_size, yaw));
  }
  return sequence;
}

TEST(StitchMany, JoinsATurnSequenceToTheExpectedWidth) {
  const TurnSequence sequence = makeTurnSequence();
  const StitchResult stitched = stitchMany(sequence.views, MatchOptions());
  ASSERT_TRUE(stitched.ok()) << stitched.error;
  ASSERT_EQ(stitched.pairs.size(), 3u);
  std::printf("cv::Stitcher panorama %d x %d, expected width %.1f\n", stitched.panorama.cols,
              stitched.panorama.rows, sequence.expectedWidth());
  EXPECT_NEAR(stitched.panorama.cols, sequence.expectedWidth(), 0.05 * sequence.expectedWidth());
}

TEST(StitchByRotation, JoinsATurnSequenceByItsYawsToTheExpectedWidth) {
  const TurnSequence sequence = makeTurnSequence();
  TurningCamera camera;
  camera.fx = camera.fy = sequence.f;
  camera.cx = sequence.view_size.width / 2.0;
  camera.cy = sequence.view_size.height / 2.0;
  const StitchResult stitched = stitchByRotation(sequence.views, sequence.yaws, camera);
  ASSERT_TRUE(stitched.ok()) << stitched.error;
  std::printf("rotation panorama %d x %d, expected width %.1f\n", stitched.panorama.cols,
              stitched.panorama.rows, sequence.expectedWidth());
  EXPECT_NEAR(stitched.panorama.cols, sequence.expectedWidth(), 3.0);
}

TEST(StitchByRotation, PutsWhatIsLeftOfTheRobotOnTheLeft) {
  // A featureless world but for one red disc seen only by the left-most view.
  cv::Mat cylinder(700, 1500, CV_8UC3, cv::Scalar(200, 200, 200));
  cylinder(cv::Rect(0, 350, 1500, 350)).setTo(cv::Scalar(120, 120, 120));
  const TurnSequence geometry;
  const int red_column = static_cast<int>(750 - geometry.f * 45.0 * kPi / 180.0);
  cv::circle(cylinder, cv::Point(red_column, 350), 20, cv::Scalar(0, 0, 230), cv::FILLED);
  std::vector<cv::Mat> views;
  for (double yaw : geometry.yaws) {
    views.push_back(cylinderView(cylinder, geometry.f, geometry.view_size, yaw));
  }
  TurningCamera camera;
  camera.fx = camera.fy = geometry.f;
  camera.cx = 320;
  camera.cy = 240;
  const StitchResult stitched = stitchByRotation(views, geometry.yaws, camera);
  ASSERT_TRUE(stitched.ok()) << stitched.error;
  cv::Mat red;
  cv::inRange(stitched.panorama, cv::Scalar(0, 0, 150), cv::Scalar(80, 80, 255), red);
  const cv::Moments moments = cv::moments(red, true);
  ASSERT_GT(moments.m00, 100.0);
  // 45 deg left of the middle heading: f * (pi/4 - 0) from the centre column.
  const double expected = stitched.panorama.cols / 2.0 - geometry.f * 45.0 * kPi / 180.0;
  EXPECT_NEAR(moments.m10 / moments.m00, expected, 3.0);
}

TEST(StitchFailures, NoOverlapIsAnError) {
  const cv::Mat scene = texturedScene(cv::Size(1200, 400), 3);
  const cv::Mat left = scene(cv::Rect(0, 0, 400, 400)).clone();
  const cv::Mat right = scene(cv::Rect(800, 0, 400, 400)).clone();
  const StitchResult pair = stitchPair(left, right, MatchOptions());
  EXPECT_FALSE(pair.ok());
  EXPECT_TRUE(pair.panorama.empty());
  EXPECT_NE(pair.error.find("overlap"), std::string::npos) << pair.error;
  const StitchResult many = stitchMany({left, right}, MatchOptions());
  EXPECT_FALSE(many.ok());
  EXPECT_NE(many.error.find("images 1 and 2"), std::string::npos) << many.error;
}

TEST(StitchFailures, BlankImageIsAnError) {
  const cv::Mat scene = texturedScene(cv::Size(400, 400), 5);
  const cv::Mat blank(400, 400, CV_8UC3, cv::Scalar(90, 90, 90));
  const StitchResult pair = stitchPair(scene, blank, MatchOptions());
  EXPECT_FALSE(pair.ok());
  EXPECT_NE(pair.error.find("image B is blank"), std::string::npos) << pair.error;
  const StitchResult many = stitchMany({scene, scene, blank}, MatchOptions());
  EXPECT_NE(many.error.find("image 3 is blank"), std::string::npos) << many.error;
}

TEST(StitchFailures, OneImageOrAnEmptyOneIsAnError) {
  const cv::Mat scene = texturedScene(cv::Size(400, 400), 5);
  EXPECT_NE(stitchMany({scene}, MatchOptions()).error.find("at least two"), std::string::npos);
  EXPECT_NE(stitchPair(scene, cv::Mat(), MatchOptions()).error.find("image B is empty"),
            std::string::npos);
  EXPECT_NE(stitchByRotation({scene}, {0.0}, TurningCamera{500, 500, 200, 200, 0})
                .error.find("at least two"),
            std::string::npos);
  EXPECT_NE(stitchByRotation({scene, scene}, {0.0}, TurningCamera{500, 500, 200, 200, 0})
                .error.find("yaws"),
            std::string::npos);
  EXPECT_NE(stitchByRotation({scene, scene}, {0.0, 0.3}, TurningCamera()).error.find("fx"),
            std::string::npos);
}

TEST(MatchOptions, RejectsUnusableValues) {
  EXPECT_EQ(validate(MatchOptions()), "");
  MatchOptions too_few;
  too_few.min_inliers = 3;
  EXPECT_EQ(validate(too_few), "min_inliers must be >= 4, got 3 (a homography needs 4 points)");
  MatchOptions any_match;
  any_match.ratio = 1.5;
  EXPECT_EQ(validate(any_match), "ratio must be in (0, 1], got 1.5");
  EXPECT_EQ(parseDetector("sift"), Detector::kSift);
  EXPECT_EQ(parseDetector("akaze"), Detector::kAkaze);
  EXPECT_EQ(parseDetector("surf"), std::nullopt);
  EXPECT_EQ(detectorName(Detector::kOrb), "orb");
}

// A plane receding to the right, B's horizon 625 px right of its left edge: B's left edge is
// enlarged 1.5 times, its right edge 7.5 (vertically) to 37.5 times (local area scale 2.25
// against 281), a true view that a fixed area-scale limit of 16 at B's corners refused.
const cv::Matx33d kStrongPerspective(1.5, 0.0, 0.0, 0.0, 1.5, 0.0, -0.0016, 0.0, 1.0);
const cv::Size kViewB(500, 400);
const std::vector<cv::Point2f> kMatchedB{{100, 100}, {400, 100}, {400, 300}, {100, 300}};

TEST(HomographyDefect, AcceptsAStrongTruePerspective) {
  EXPECT_EQ(homographyDefect(kStrongPerspective, kViewB, kMatchedB), "");
  EXPECT_EQ(homographyDefect(-kStrongPerspective, kViewB, kMatchedB), "") << "sign is free";
}

TEST(HomographyDefect, RejectsAHorizonCrossingB) {
  const cv::Matx33d beyond(1, 0, 0, 0, 1, 0, -0.003, 0, 1);  // w = 0 at x = 333 px
  EXPECT_NE(homographyDefect(beyond, kViewB, kMatchedB).find("horizon"), std::string::npos);
}

TEST(HomographyDefect, RejectsAMirror) {
  const cv::Matx33d mirror(-1, 0, 500, 0, 1, 0, 0, 0, 1);
  EXPECT_NE(homographyDefect(mirror, kViewB, kMatchedB).find("mirrors"), std::string::npos);
}

TEST(HomographyDefect, RejectsCollapsingTheMatchedRegionOntoALine) {
  const cv::Matx33d squash(1, 0, 0, 0, 0.05, 0, 0, 0, 1);
  EXPECT_NE(homographyDefect(squash, kViewB, kMatchedB).find("squashes"), std::string::npos);
}

TEST(MatchOptions, RejectsHoldingOutEveryInlier) {
  MatchOptions options;
  options.held_out_every = 1;
  EXPECT_EQ(validate(options), "held_out_every must be >= 2, got 1 (1 would hold out all)");
  options.held_out_every = 2;
  EXPECT_EQ(validate(options), "");
}

TEST(RatioTestMatches, KeepsOnlyUnambiguousNearestNeighbours) {
  // 1-D descriptors: query 0.0 is nearest 0.1, the next at 1.0 (kept); 2.0 is midway between
  // 1.9 and 2.1 (ambiguous, dropped); 1.05 is nearest 1.0 (kept). One train row: no second
  // neighbour, nothing kept.
  const cv::Mat train = (cv::Mat_<float>(4, 1) << 0.1f, 1.0f, 1.9f, 2.1f);
  const cv::Mat query = (cv::Mat_<float>(3, 1) << 0.0f, 2.0f, 1.05f);
  const cv::BFMatcher matcher(cv::NORM_L2);
  const std::vector<cv::DMatch> matches = ratioTestMatches(matcher, query, train, 0.75);
  ASSERT_EQ(matches.size(), 2u);
  EXPECT_EQ(matches[0].queryIdx, 0);
  EXPECT_EQ(matches[0].trainIdx, 0);
  EXPECT_EQ(matches[1].queryIdx, 2);
  EXPECT_EQ(matches[1].trainIdx, 1);
  EXPECT_TRUE(ratioTestMatches(matcher, query, train.rowRange(0, 1), 0.75).empty());
}

}  // namespace
}  // namespace image_converter
