// Feature matching between two views: keypoints, ratio-tested matches and a RANSAC homography.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "follow_bot_common/config_fields.h"
#include "follow_bot_common/enum_names.h"
#include "image_converter/MatchingDefaults.h"

namespace image_converter {

enum class Detector { kOrb, kSift, kAkaze };
inline constexpr follow_bot_common::EnumName<Detector> kDetectorNames[] = {
    {Detector::kOrb, "orb"}, {Detector::kSift, "sift"}, {Detector::kAkaze, "akaze"}};

// "orb", "sift" or "akaze" (lower case); nothing for anything else.
inline std::optional<Detector> parseDetector(std::string_view name) {
  return follow_bot_common::valueIn(kDetectorNames, name);
}
inline std::string detectorName(Detector detector) {
  return follow_bot_common::nameIn(kDetectorNames, detector);
}
// At compile time: any other name throws, which in a constant expression is a compile error, so
// a new name in cfg/Matching.cfg cannot silently mean one of these.
constexpr Detector detectorNamed(std::string_view name) {
  if (const auto detector = follow_bot_common::valueIn(kDetectorNames, name)) return *detector;
  throw std::invalid_argument("no such detector");
}
// cfg/Matching.cfg's default detector (MatchingDefaults, generated), evaluated at compile time.
inline constexpr Detector kDefaultDetector = detectorNamed(MatchingDefaults::detector);

// Defaults of detector and min_inliers: cfg/Matching.cfg's (MatchingDefaults, generated).
struct MatchOptions {
  Detector detector = kDefaultDetector;
  int max_features = 4000;           // keypoints kept per image
  double ratio = 0.75;               // Lowe's ratio test: best / second-best distance below this
  double ransac_threshold_px = 3.0;  // inlier tolerance of the RANSAC homography
  // Fewer inliers: the views are taken not to overlap.
  int min_inliers = MatchingDefaults::min_inliers;
  double min_contrast = 2.0;  // grey-level standard deviation below this: a blank image
  // Refine the RANSAC homography by dense ECC alignment of the overlap (cv::findTransformECC):
  // keypoints sit on a coarse pyramid grid (ORB), the aligned pixels do not. The refinement is
  // kept only when it lowers the error on inlier matches held out of the fit (see matchPair).
  bool refine = true;
  int held_out_every = 5;  // every n-th RANSAC inlier is held out to judge the refinement

  static constexpr auto fields() {
    using C = MatchOptions;
    using follow_bot_common::atLeast;
    return std::make_tuple(
        follow_bot_common::field("max_features", &C::max_features, atLeast(10)),
        follow_bot_common::field("ratio", &C::ratio, follow_bot_common::aboveAtMost(0.0, 1.0)),
        follow_bot_common::field("ransac_threshold_px", &C::ransac_threshold_px,
                                 follow_bot_common::positive()),
        follow_bot_common::cfgField("min_inliers", &C::min_inliers,
                                    atLeast(4).because("a homography needs 4 points")),
        follow_bot_common::field("min_contrast", &C::min_contrast, atLeast(0.0)),
        follow_bot_common::field("refine", &C::refine),
        follow_bot_common::field("held_out_every", &C::held_out_every,
                                 atLeast(2).because("1 would hold out all")));
  }
};

// Empty when the options are usable, otherwise a message naming the first bad field.
std::string validate(const MatchOptions& options);

// The homography between two views, or why there is none.
struct PairMatch {
  std::string error;  // empty when the homography is trustworthy
  // Maps pixels of image B into image A's pixel frame: a ~ H * b (homogeneous).
  cv::Matx33d homography = cv::Matx33d::eye();
  int keypoints_a = 0;
  int keypoints_b = 0;
  int matches = 0;  // after the ratio test
  int inliers = 0;
  double reprojection_error_px = 0.0;  // RMS over inliers of |H b - a|
  bool refined = false;  // the homography is ECC's (it lowered the held-out error), not RANSAC's
  // The refinement's judgement: how many inliers were held out of the fit (0: not judged, the
  // refinement is off or there were too few inliers), and the median of |H b - a| over them for
  // the RANSAC fit of the other inliers and for its ECC refinement (none when ECC failed).
  int held_out_matches = 0;
  double held_out_median_ransac_px = 0.0;
  std::optional<double> held_out_median_refined_px;
  bool ok() const { return error.empty(); }
};

// The configured keypoint detector and descriptor (ORB or SIFT with max_features keypoints,
// AKAZE with its own detection threshold).
cv::Ptr<cv::Feature2D> createDetector(const MatchOptions& options);

// Empty when `image` is usable for matching (non-empty, 8-bit grey/BGR/BGRA, not blank),
// otherwise the reason, naming the image by `label`.
std::string checkImage(const cv::Mat& image, const std::string& label, double min_contrast);

// Lowe's ratio test: for each query descriptor its nearest train descriptor, kept only when
// closer than `ratio` times the second nearest (an unambiguous match).
std::vector<cv::DMatch> ratioTestMatches(const cv::DescriptorMatcher& matcher, const cv::Mat& query,
                                         const cv::Mat& train, double ratio);

// Empty when `homography` (B into A) is one a camera can make, otherwise why not: its horizon
// (where it sends points to infinity) crosses image B, it mirrors B, or over `matched_b` (the
// matched keypoints of B, the overlap actually used) it squashes a direction more than the
// descriptors that matched there tolerate (condition number of the local Jacobian). A strong
// perspective, whose local scale differs many times from one side of B to the other, is
// none of these.
std::string homographyDefect(const cv::Matx33d& homography, const cv::Size& size_b,
                             const std::vector<cv::Point2f>& matched_b);

// Matches image B against image A (8-bit grey, BGR or BGRA): ratio-tested matches, a RANSAC
// homography, and, with options.refine, its ECC refinement when that generalises: every
// held_out_every-th inlier is held out, RANSAC is fitted to the others and refined by ECC, and
// only if the refinement lowers the median error on the held-out matches (at their sub-pixel
// corners) is the RANSAC homography of all inliers replaced by its ECC refinement. Never
// throws on bad input: the result carries the error (blank image, too few features or inliers,
// degenerate homography).
PairMatch matchPair(const cv::Mat& a, const cv::Mat& b, const MatchOptions& options);

// The pixel a homography maps `point` to.
cv::Point2d applyHomography(const cv::Matx33d& homography, const cv::Point2d& point);

}  // namespace image_converter
