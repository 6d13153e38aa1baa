#include "image_converter/feature_matching.h"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "channels.h"

namespace image_converter {
namespace {

// Refines `h` (B into A) by maximising the enhanced correlation coefficient between A and B
// warped into A's frame, over their overlap. Returns false (leaving `h` alone) when ECC fails or
// would move a corner of B by more than `max_shift_px`: then the feature estimate stands.
bool refineByEcc(const cv::Mat& grey_a, const cv::Mat& grey_b, cv::Matx33d& h,
                 double max_shift_px) {
  cv::Mat warped_b, overlap;
  cv::warpPerspective(grey_b, warped_b, h, grey_a.size(), cv::INTER_LINEAR);
  cv::warpPerspective(cv::Mat(grey_b.size(), CV_8U, cv::Scalar(255)), overlap, h, grey_a.size(),
                      cv::INTER_NEAREST);
  cv::erode(overlap, overlap, cv::Mat(), cv::Point(-1, -1), 2);  // no border pixels
  if (cv::countNonZero(overlap) < 1000) return false;
  // ECC's warp W maps A's pixels into the warped B: A(x) ~ warped_b(W x) = B(h^-1 W x).
  cv::Mat correction = cv::Mat::eye(3, 3, CV_32F);
  try {
    cv::findTransformECC(
        grey_a, warped_b, correction, cv::MOTION_HOMOGRAPHY,
        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-6), overlap, 3);
  } catch (const cv::Exception&) {
    return false;  // did not converge
  }
  const cv::Matx33d refined = cv::Matx33d(cv::Mat_<double>(correction)).inv() * h;
  for (const cv::Point2d& corner :
       {cv::Point2d(0, 0), cv::Point2d(grey_b.cols, 0), cv::Point2d(grey_b.cols, grey_b.rows),
        cv::Point2d(0, grey_b.rows)}) {
    if (cv::norm(applyHomography(refined, corner) - applyHomography(h, corner)) > max_shift_px) {
      return false;
    }
  }
  h = refined * (1.0 / refined(2, 2));
  return true;
}

// RANSAC settings shared by the full fit and the held-out judgement's fit.
constexpr int kRansacIterations = 5000;
constexpr double kRansacConfidence = 0.999;
// Fewer held-out matches than this say nothing about the refinement: it is not tried.
constexpr std::size_t kMinHeldOut = 4;

// RMS over the matches of |H b - a| (px).
double rmsError(const cv::Matx33d& h, const std::vector<cv::Point2f>& points_b,
                const std::vector<cv::Point2f>& points_a) {
  double squared_sum = 0.0;
  for (std::size_t i = 0; i < points_b.size(); ++i) {
    const cv::Point2d error = applyHomography(h, points_b[i]) - cv::Point2d(points_a[i]);
    squared_sum += error.dot(error);
  }
  return points_b.empty() ? 0.0 : std::sqrt(squared_sum / points_b.size());
}

// Median over the (non-empty) matches of |H b - a| (px).
double medianError(const cv::Matx33d& h, const std::vector<cv::Point2f>& points_b,
                   const std::vector<cv::Point2f>& points_a) {
  std::vector<double> errors;
  for (std::size_t i = 0; i < points_b.size(); ++i) {
    errors.push_back(cv::norm(applyHomography(h, points_b[i]) - cv::Point2d(points_a[i])));
  }
  const auto middle = errors.begin() + errors.size() / 2;
  std::nth_element(errors.begin(), middle, errors.end());
  return *middle;
}

// ECC maximises photometric agreement, which on real photographs (lighting, depth of the paint,
// a strong viewpoint change) can bend the geometry near the image borders while the centre
// agrees. So the refinement must earn its place on matches neither estimate has seen: every
// held_out_every-th inlier (inliers come in keypoint order, so these spread over the image) is
// held out, RANSAC is fitted to the rest and refined by ECC, and only if that lowers the
// held-out error is `result.homography` (the RANSAC fit of all inliers) refined by ECC too.
// The judge must see sub-pixel differences, which raw keypoints cannot: ORB's sit on their
// pyramid level's grid (up to +-0.5 * 1.2^level px), a bias RANSAC fits and ECC does not. So
// each held-out point is first moved to its sub-pixel corner (cv::cornerSubPix, in both
// images; a corner stays a corner under a homography). The error is then the median, not the
// RMS: it stays heavy-tailed (blob-like keypoints have no corner to snap to), and the RMS,
// ruled by those few, favours the least-squares fit. Measured: on rendered views this keeps
// ECC's sub-pixel homography (judged at raw keypoints, a 300 px shift kept RANSAC's, 1.8 px
// off at a corner); on the graffiti pair it rejects ECC, 3.4 px off near the borders where
// RANSAC is 2.4 px.
void refineWhereHeldOutMatchesAgree(const cv::Mat& grey_a, const cv::Mat& grey_b,
                                    const std::vector<cv::Point2f>& inliers_a,
                                    const std::vector<cv::Point2f>& inliers_b,
                                    const MatchOptions& options, PairMatch& result) {
  std::vector<cv::Point2f> fit_a, fit_b, held_a, held_b;
  for (std::size_t i = 0; i < inliers_a.size(); ++i) {
    const bool held = (i + 1) % options.held_out_every == 0;
    (held ? held_a : fit_a).push_back(inliers_a[i]);
    (held ? held_b : fit_b).push_back(inliers_b[i]);
  }
  if (held_a.size() < kMinHeldOut) return;
  const cv::TermCriteria subpixel_stop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 40, 1e-3);
  cv::cornerSubPix(grey_a, held_a, cv::Size(3, 3), cv::Size(-1, -1), subpixel_stop);
  cv::cornerSubPix(grey_b, held_b, cv::Size(3, 3), cv::Size(-1, -1), subpixel_stop);
  const cv::Mat fitted = cv::findHomography(fit_b, fit_a, cv::RANSAC, options.ransac_threshold_px,
                                            cv::noArray(), kRansacIterations, kRansacConfidence);
  if (fitted.empty()) return;
  cv::Matx33d candidate(fitted);
  result.held_out_matches = static_cast<int>(held_a.size());
  result.held_out_median_ransac_px = medianError(candidate, held_b, held_a);
  // ECC may move a corner of B by up to 10 RANSAC thresholds; more is a wrong alignment.
  const double max_shift_px = 10.0 * options.ransac_threshold_px;
  if (!refineByEcc(grey_a, grey_b, candidate, max_shift_px)) return;
  result.held_out_median_refined_px = medianError(candidate, held_b, held_a);
  if (*result.held_out_median_refined_px < result.held_out_median_ransac_px) {
    // The refinement has earned its place; the one kept starts, like the RANSAC homography it
    // replaces, from all inliers (ECC lands a little differently from each start), unless ECC
    // fails from there.
    cv::Matx33d refined_from_all = result.homography;
    const bool converged = refineByEcc(grey_a, grey_b, refined_from_all, max_shift_px);
    result.homography = converged ? refined_from_all : candidate;
    result.refined = true;
  }
}

}  // namespace

cv::Ptr<cv::Feature2D> createDetector(const MatchOptions& options) {
  switch (options.detector) {
    case Detector::kSift:
      return cv::SIFT::create(options.max_features);
    case Detector::kAkaze:
      return cv::AKAZE::create();
    case Detector::kOrb:
      break;
  }
  return cv::ORB::create(options.max_features);
}

std::string homographyDefect(const cv::Matx33d& homography, const cv::Size& size_b,
                             const std::vector<cv::Point2f>& matched_b) {
  // A homography is defined up to its sign: take the one with w > 0 at B's centre.
  const cv::Point2d centre(size_b.width / 2.0, size_b.height / 2.0);
  const double w_centre =
      homography(2, 0) * centre.x + homography(2, 1) * centre.y + homography(2, 2);
  const cv::Matx33d h = w_centre < 0.0 ? -homography : homography;
  // w is linear in the pixel, so positive at B's four corners means positive over all of B.
  for (const cv::Point2d& corner :
       {cv::Point2d(0, 0), cv::Point2d(size_b.width, 0), cv::Point2d(size_b.width, size_b.height),
        cv::Point2d(0, size_b.height)}) {
    if (!(h(2, 0) * corner.x + h(2, 1) * corner.y + h(2, 2) > 0.0)) {
      return "the homography is degenerate (its horizon crosses image B)";
    }
  }
  // With w > 0 the local Jacobian's determinant, det(h) / w^3, has the sign of det(h).
  if (!(cv::determinant(h) > 0.0)) return "the homography is degenerate (it mirrors image B)";
  // Descriptors match a patch only while its shape survives: SIFT, ORB and AKAZE fail beyond a
  // foreshortening of about 3 (a 70 degree tilt). A fit that squashes a direction far more
  // than that where its own matches are contradicts them. Vertices of the matched region's
  // hull suffice: the squash grows towards the horizon, away from the region's inside.
  constexpr double kMaxCondition = 10.0;
  std::vector<cv::Point2f> hull;
  if (matched_b.size() >= 3) cv::convexHull(matched_b, hull);
  for (const cv::Point2f& p : hull) {
    const double w = h(2, 0) * p.x + h(2, 1) * p.y + h(2, 2);
    const cv::Point2d mapped = applyHomography(h, p);
    const cv::Matx22d jacobian(
        (h(0, 0) - mapped.x * h(2, 0)) / w, (h(0, 1) - mapped.x * h(2, 1)) / w,
        (h(1, 0) - mapped.y * h(2, 0)) / w, (h(1, 1) - mapped.y * h(2, 1)) / w);
    cv::Vec2d singular_values;
    cv::SVD::compute(jacobian, singular_values, cv::SVD::NO_UV);
    const double condition = singular_values[0] / singular_values[1];
    if (!(condition <= kMaxCondition)) {
      return "the homography is degenerate (it squashes the matched region " +
             std::to_string(condition) + " times more in one direction than in the other)";
    }
  }
  return "";
}

std::string validate(const MatchOptions& options) {
  return follow_bot_common::checkFields(options);
}

std::string checkImage(const cv::Mat& image, const std::string& label, double min_contrast) {
  if (image.empty()) return label + " is empty";
  if (image.depth() != CV_8U ||
      (image.channels() != 1 && image.channels() != 3 && image.channels() != 4)) {
    return label + " is not an 8-bit grey, BGR or BGRA image";
  }
  cv::Scalar mean, stddev;
  cv::meanStdDev(withChannels(image, 1), mean, stddev);
  if (stddev[0] < min_contrast) {
    return label + " is blank (grey-level standard deviation " + std::to_string(stddev[0]) + ")";
  }
  return "";
}

cv::Point2d applyHomography(const cv::Matx33d& h, const cv::Point2d& p) {
  const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1.0);
  return {q[0] / q[2], q[1] / q[2]};
}

std::vector<cv::DMatch> ratioTestMatches(const cv::DescriptorMatcher& matcher, const cv::Mat& query,
                                         const cv::Mat& train, double ratio) {
  std::vector<std::vector<cv::DMatch>> candidates;
  matcher.knnMatch(query, train, candidates, 2);
  std::vector<cv::DMatch> matches;
  for (const std::vector<cv::DMatch>& pair : candidates) {
    if (pair.size() == 2 && pair[0].distance < ratio * pair[1].distance) {
      matches.push_back(pair[0]);
    }
  }
  return matches;
}

PairMatch matchPair(const cv::Mat& a, const cv::Mat& b, const MatchOptions& options) {
  PairMatch result;
  result.error = validate(options);
  if (result.error.empty()) result.error = checkImage(a, "image A", options.min_contrast);
  if (result.error.empty()) result.error = checkImage(b, "image B", options.min_contrast);
  if (!result.ok()) return result;

  const cv::Ptr<cv::Feature2D> detector = createDetector(options);
  std::vector<cv::KeyPoint> keypoints_a, keypoints_b;
  cv::Mat descriptors_a, descriptors_b;
  const cv::Mat grey_a = withChannels(a, 1), grey_b = withChannels(b, 1);
  detector->detectAndCompute(grey_a, cv::noArray(), keypoints_a, descriptors_a);
  detector->detectAndCompute(grey_b, cv::noArray(), keypoints_b, descriptors_b);
  result.keypoints_a = static_cast<int>(keypoints_a.size());
  result.keypoints_b = static_cast<int>(keypoints_b.size());
  if (result.keypoints_a < options.min_inliers || result.keypoints_b < options.min_inliers) {
    result.error = "too few features (" + std::to_string(result.keypoints_a) + " in A, " +
                   std::to_string(result.keypoints_b) + " in B; need " +
                   std::to_string(options.min_inliers) + ")";
    return result;
  }

  // SIFT's descriptors are real vectors, ORB's and AKAZE's bit strings.
  const int norm = options.detector == Detector::kSift ? cv::NORM_L2 : cv::NORM_HAMMING;
  cv::BFMatcher matcher(norm);
  std::vector<cv::Point2f> points_a, points_b;
  for (const cv::DMatch& match :
       ratioTestMatches(matcher, descriptors_b, descriptors_a, options.ratio)) {
    points_b.push_back(keypoints_b[match.queryIdx].pt);
    points_a.push_back(keypoints_a[match.trainIdx].pt);
  }
  result.matches = static_cast<int>(points_a.size());
  if (result.matches < options.min_inliers) {
    result.error = "too few matches after the ratio test (" + std::to_string(result.matches) +
                   ", need " + std::to_string(options.min_inliers) +
                   "): the images do not seem to overlap";
    return result;
  }

  std::vector<unsigned char> inlier_mask;
  const cv::Mat h = cv::findHomography(points_b, points_a, cv::RANSAC, options.ransac_threshold_px,
                                       inlier_mask, kRansacIterations, kRansacConfidence);
  if (h.empty()) {
    result.error = "no homography fits the matches: the images do not seem to overlap";
    return result;
  }
  result.homography = cv::Matx33d(h);
  std::vector<cv::Point2f> inliers_a, inliers_b;
  for (std::size_t i = 0; i < inlier_mask.size(); ++i) {
    if (!inlier_mask[i]) continue;
    inliers_a.push_back(points_a[i]);
    inliers_b.push_back(points_b[i]);
  }
  result.inliers = static_cast<int>(inliers_a.size());
  if (options.refine && result.inliers >= options.min_inliers) {
    refineWhereHeldOutMatchesAgree(grey_a, grey_b, inliers_a, inliers_b, options, result);
  }
  result.reprojection_error_px = rmsError(result.homography, inliers_b, inliers_a);
  if (result.inliers < options.min_inliers) {
    result.error = "too few RANSAC inliers (" + std::to_string(result.inliers) + " of " +
                   std::to_string(result.matches) + " matches, need " +
                   std::to_string(options.min_inliers) + "): the images do not seem to overlap";
    return result;
  }
  result.error = homographyDefect(result.homography, b.size(), inliers_b);
  return result;
}

}  // namespace image_converter
