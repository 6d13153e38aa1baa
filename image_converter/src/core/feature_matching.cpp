#include "image_converter/feature_matching.h"

#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

namespace image_converter {
namespace {

cv::Mat toGrey(const cv::Mat& image) {
  if (image.channels() == 1) return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return grey;
}

// A homography that flips, collapses or explodes the image is a RANSAC accident, not a view
// change a camera can make: the local scale must stay within 1/kMaxScale..kMaxScale.
std::string checkConditioning(const cv::Matx33d& h, const cv::Size& size_b) {
  constexpr double kMaxScale = 4.0;
  for (const cv::Point2d& corner :
       {cv::Point2d(0, 0), cv::Point2d(size_b.width, 0), cv::Point2d(size_b.width, size_b.height),
        cv::Point2d(0, size_b.height)}) {
    const double w = h(2, 0) * corner.x + h(2, 1) * corner.y + h(2, 2);
    if (!(w > 1e-6)) return "the homography sends a corner of image B to infinity";
    // Determinant of the Jacobian of the projective map at this corner.
    const double jacobian = cv::determinant(h) / (w * w * w);
    if (!(jacobian > 1.0 / (kMaxScale * kMaxScale) && jacobian < kMaxScale * kMaxScale)) {
      return "the homography is degenerate (local area scale " + std::to_string(jacobian) + ")";
    }
  }
  return "";
}

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

}  // namespace

cv::Ptr<cv::Feature2D> createDetector(const MatchOptions& options) {
  if (options.detector == Detector::kSift) return cv::SIFT::create(options.max_features);
  return cv::ORB::create(options.max_features);
}

bool parseDetector(const std::string& name, Detector& detector) {
  if (name == "orb") {
    detector = Detector::kOrb;
  } else if (name == "sift") {
    detector = Detector::kSift;
  } else {
    return false;
  }
  return true;
}

std::string detectorName(Detector detector) { return detector == Detector::kSift ? "sift" : "orb"; }

std::string validate(const MatchOptions& options) {
  if (options.max_features < 10) return "max_features must be >= 10";
  if (!(options.ratio > 0.0 && options.ratio <= 1.0)) return "ratio must be in (0, 1]";
  if (!(options.ransac_threshold_px > 0.0)) return "ransac_threshold_px must be > 0";
  if (options.min_inliers < 4) return "min_inliers must be >= 4 (a homography needs 4 points)";
  if (!(options.min_contrast >= 0.0)) return "min_contrast must be >= 0";
  return "";
}

std::string checkImage(const cv::Mat& image, const std::string& label, double min_contrast) {
  if (image.empty()) return label + " is empty";
  if (image.depth() != CV_8U ||
      (image.channels() != 1 && image.channels() != 3 && image.channels() != 4)) {
    return label + " is not an 8-bit grey, BGR or BGRA image";
  }
  cv::Scalar mean, stddev;
  cv::meanStdDev(toGrey(image), mean, stddev);
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
  const cv::Mat grey_a = toGrey(a), grey_b = toGrey(b);
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
                                       inlier_mask, 5000, 0.999);
  if (h.empty()) {
    result.error = "no homography fits the matches: the images do not seem to overlap";
    return result;
  }
  result.homography = cv::Matx33d(h);
  const int ransac_inliers = cv::countNonZero(inlier_mask);
  if (options.refine && ransac_inliers >= options.min_inliers) {
    result.refined =
        refineByEcc(grey_a, grey_b, result.homography, 10.0 * options.ransac_threshold_px);
  }
  double squared_sum = 0.0;
  for (std::size_t i = 0; i < inlier_mask.size(); ++i) {
    if (!inlier_mask[i]) continue;
    ++result.inliers;
    const cv::Point2d error =
        applyHomography(result.homography, points_b[i]) - cv::Point2d(points_a[i]);
    squared_sum += error.dot(error);
  }
  result.reprojection_error_px = result.inliers > 0 ? std::sqrt(squared_sum / result.inliers) : 0.0;
  if (result.inliers < options.min_inliers) {
    result.error = "too few RANSAC inliers (" + std::to_string(result.inliers) + " of " +
                   std::to_string(result.matches) + " matches, need " +
                   std::to_string(options.min_inliers) + "): the images do not seem to overlap";
    return result;
  }
  result.error = checkConditioning(result.homography, b.size());
  return result;
}

}  // namespace image_converter
