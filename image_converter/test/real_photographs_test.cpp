// Matching on real photographs with a ground-truth homography: the Oxford "graffiti" viewpoint
// pair shipped by Debian's opencv-doc (tools/debian-packages.txt).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>

#include "image_converter/feature_matching.h"

namespace image_converter {
namespace {

const std::string kDataDir = "/usr/share/doc/opencv-doc/examples/data/";
// The margin each border band is wide, for the error near the image edges.
constexpr double kBorderBand = 50.0;

struct Graffiti {
  cv::Mat graf1, graf3;
  cv::Matx33d graf1_to_graf3;  // the dataset's ground truth (H1to3p)
};

// Empty images when opencv-doc is missing; the test then fails naming the package.
Graffiti loadGraffiti() {
  Graffiti pair;
  pair.graf1 = cv::imread(kDataDir + "graf1.png", cv::IMREAD_COLOR);
  pair.graf3 = cv::imread(kDataDir + "graf3.png", cv::IMREAD_COLOR);
  cv::FileStorage truth(kDataDir + "H1to3p.xml", cv::FileStorage::READ);
  if (truth.isOpened()) {
    cv::Mat h;
    truth["H13"] >> h;
    if (h.rows == 3 && h.cols == 3) pair.graf1_to_graf3 = cv::Matx33d(h);
  }
  return pair;
}

struct GridError {
  int points = 0;
  double median = 0.0, max = 0.0, max_near_border = 0.0;
};

// 0, step, 2 step, ... and the last pixel, so the grid reaches both borders.
std::vector<double> gridCoordinates(int size, double step) {
  std::vector<double> coordinates;
  for (double c = 0.0; c < size - 1; c += step) coordinates.push_back(c);
  coordinates.push_back(size - 1);
  return coordinates;
}

// `stitch graf1.png graf3.png` warps graf3 into graf1's frame by `graf3_to_graf1`, so a graf1
// pixel p lands at H(H_true p): the panorama's misregistration is |H(H_true p) - p| in graf1
// pixels. Measured on a 4 px grid over all of graf1 (borders included) that H_true maps inside
// graf3; the border band is the outer kBorderBand px of graf1.
GridError errorOverGraf1(const Graffiti& pair, const cv::Matx33d& graf3_to_graf1) {
  std::vector<double> errors;
  GridError result;
  const double last_x = pair.graf1.cols - 1, last_y = pair.graf1.rows - 1;
  for (const double y : gridCoordinates(pair.graf1.rows, 4.0)) {
    for (const double x : gridCoordinates(pair.graf1.cols, 4.0)) {
      const cv::Point2d in_graf3 = applyHomography(pair.graf1_to_graf3, {x, y});
      if (in_graf3.x < 0 || in_graf3.y < 0 || in_graf3.x > pair.graf3.cols - 1 ||
          in_graf3.y > pair.graf3.rows - 1) {
        continue;
      }
      const double error = cv::norm(applyHomography(graf3_to_graf1, in_graf3) - cv::Point2d(x, y));
      errors.push_back(error);
      result.max = std::max(result.max, error);
      if (std::min({x, y, last_x - x, last_y - y}) < kBorderBand) {
        result.max_near_border = std::max(result.max_near_border, error);
      }
    }
  }
  result.points = static_cast<int>(errors.size());
  if (errors.empty()) return result;
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  result.median = errors[errors.size() / 2];
  return result;
}

TEST(RealPhotographs, GraffitiPairWithinThreePixelsAndNoWorseThanRansacAlone) {
  const Graffiti pair = loadGraffiti();
  ASSERT_FALSE(pair.graf1.empty() || pair.graf3.empty())
      << "no graffiti pair in " << kDataDir
      << ": install opencv-doc (tools/debian-packages.txt; a dpkg path-exclude for "
         "/usr/share/doc drops it)";
  ASSERT_NE(pair.graf1_to_graf3, cv::Matx33d::eye()) << "cannot read " << kDataDir << "H1to3p.xml";

  MatchOptions options;
  options.detector = Detector::kSift;
  options.refine = false;
  const PairMatch ransac = matchPair(pair.graf1, pair.graf3, options);
  options.refine = true;
  const PairMatch gated = matchPair(pair.graf1, pair.graf3, options);
  ASSERT_TRUE(ransac.ok()) << ransac.error;
  ASSERT_TRUE(gated.ok()) << gated.error;

  const GridError ransac_error = errorOverGraf1(pair, ransac.homography);
  const GridError gated_error = errorOverGraf1(pair, gated.homography);
  std::printf(
      "graffiti 1->3, SIFT, %d grid points: RANSAC alone median %.3f max %.3f (border %.3f) px; "
      "gated (%s, held-out median %.3f px RANSAC, %.3f px ECC over %d) median %.3f max %.3f "
      "(border %.3f) px\n",
      ransac_error.points, ransac_error.median, ransac_error.max, ransac_error.max_near_border,
      gated.refined ? "ECC kept" : "RANSAC kept", gated.held_out_median_ransac_px,
      gated.held_out_median_refined_px.value_or(-1.0), gated.held_out_matches, gated_error.median,
      gated_error.max, gated_error.max_near_border);

  // graf3 sees 97 % of graf1 (31506 of the 32361 grid points): the grid covers the borders.
  EXPECT_GT(gated_error.points, 30000);
  // Measured (OpenCV 4.6, this grid): RANSAC alone and gated both median 0.38 px, max 2.41 px
  // (in the border band); ECC always was median 0.65 px, max 3.38 px. The bound on the max is
  // the 3 px goal (0.59 px of margin), the median's keeps 0.12 px of margin.
  EXPECT_LE(gated_error.max, 3.0);
  EXPECT_LE(gated_error.median, 0.5);
  // Never worse than RANSAC alone on this pair, at the median or at the worst grid point.
  EXPECT_LE(gated_error.max, ransac_error.max + 1e-9);
  EXPECT_LE(gated_error.median, ransac_error.median + 1e-9);
  // Why: ECC's homography fits the held-out matches worse, so RANSAC's is kept.
  EXPECT_FALSE(gated.refined);
  EXPECT_GE(gated.held_out_matches, 50);
  ASSERT_TRUE(gated.held_out_median_refined_px.has_value());
  EXPECT_GT(*gated.held_out_median_refined_px, gated.held_out_median_ransac_px);
}

// The default detector (cfg/Matching.cfg) on the graffiti pair in both orders: the median
// misregistration over the panorama's first image within the 1.5 px goal. Measured (OpenCV 4.6,
// ECC gate on): ORB 0.79 px with graf1 first, 0.93 px with graf3 first; SIFT 0.38 and 2.06 px,
// AKAZE 1.33 and 0.55 px, so only ORB holds the goal in both orders.
TEST(RealPhotographs, GraffitiPairWithinOneAndAHalfPixelsInBothOrdersWithTheDefaultDetector) {
  const Graffiti pair = loadGraffiti();
  ASSERT_FALSE(pair.graf1.empty() || pair.graf3.empty()) << "install opencv-doc";
  const PairMatch forward = matchPair(pair.graf1, pair.graf3, MatchOptions());
  const PairMatch backward = matchPair(pair.graf3, pair.graf1, MatchOptions());
  ASSERT_TRUE(forward.ok()) << forward.error;
  ASSERT_TRUE(backward.ok()) << backward.error;
  // graf3 first: the truth is the inverse, and graf1 plays graf3's part in errorOverGraf1.
  const Graffiti swapped{pair.graf3, pair.graf1, pair.graf1_to_graf3.inv()};
  const GridError forward_error = errorOverGraf1(pair, forward.homography);
  const GridError backward_error = errorOverGraf1(swapped, backward.homography);
  std::printf(
      "graffiti, %s: graf1 first median %.3f max %.3f px; graf3 first median %.3f max %.3f px\n",
      detectorName(kDefaultDetector).c_str(), forward_error.median, forward_error.max,
      backward_error.median, backward_error.max);
  EXPECT_LE(forward_error.median, 1.5);
  EXPECT_LE(backward_error.median, 1.5);
}

}  // namespace
}  // namespace image_converter
