#include "follow_bot/sign_detector.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "follow_bot/config_checks.h"

namespace follow_bot {
namespace {

// OpenCV's SIFT doubles the image with a resize that puts source pixel x at 2x + 0.5, but scales
// keypoints back by a plain halving, so every keypoint comes out a quarter pixel right of and
// below its true position (measured: +0.24 px on a blob of known centre). Undo it so poses are
// unbiased.
constexpr float kSiftOffsetPx = 0.25f;

// Pixels along the sign's outline left out of the ECC alignment.
constexpr int kEdgeBandPx = 4;

std::vector<cv::Point2f> keypointPositions(const std::vector<cv::KeyPoint>& keypoints) {
  std::vector<cv::Point2f> points;
  points.reserve(keypoints.size());
  for (const cv::KeyPoint& k : keypoints) {
    points.emplace_back(k.pt.x - kSiftOffsetPx, k.pt.y - kSiftOffsetPx);
  }
  return points;
}

double rotationAngle(const cv::Matx33d& a, const cv::Matx33d& b) {
  const cv::Matx33d relative = a.t() * b;
  const double c = (cv::trace(relative) - 1.0) / 2.0;
  return std::acos(std::clamp(c, -1.0, 1.0));
}

// Signed area of a polygon in pixels; positive when its vertices run clockwise on screen (image
// y points down), which is how TL, TR, BR, BL of a sign seen from the front run.
double signedArea(const std::vector<cv::Point2f>& polygon) {
  double area = 0.0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const cv::Point2f& p = polygon[i];
    const cv::Point2f& q = polygon[(i + 1) % polygon.size()];
    area += static_cast<double>(p.x) * q.y - static_cast<double>(q.x) * p.y;
  }
  return area / 2.0;
}

}  // namespace

std::string validate(const SignDetectorConfig& config) {
  if (config.image_path.empty()) return "image_path must name the sign's reference picture";
  for (const std::string& error : {
           requirePositive("width_m", config.width_m),
           requireInRange("ratio", config.ratio, 0.1, 1.0),
           requireAtLeast("min_inliers", config.min_inliers, 4),
           requirePositive("ransac_threshold_px", config.ransac_threshold_px),
           requireAtLeast("max_reference_features", config.max_reference_features, 0),
           requireAtLeast("min_reference_features", config.min_reference_features, 4),
           requireAtLeast("max_image_features", config.max_image_features, 0),
           requirePositive("max_reprojection_error_px", config.max_reprojection_error_px),
           requireAtLeast("refine_passes", config.refine_passes, 0),
           requireAtLeast("refine_iterations", config.refine_iterations, 1),
           requireInRange("min_correlation", config.min_correlation, 0.0, 1.0),
           requirePositive("max_refine_shift_px", config.max_refine_shift_px),
           requireAtLeast("ambiguity_px", config.ambiguity_px, 0.0),
       }) {
    if (!error.empty()) return error;
  }
  return "";
}

SignDetector::SignDetector(const SignDetectorConfig& config) : config_(config) {
  const std::string error = validate(config);
  if (!error.empty()) throw std::invalid_argument("sign detector: " + error);
  const cv::Mat reference = cv::imread(config.image_path, cv::IMREAD_GRAYSCALE);
  if (reference.empty()) {
    throw std::invalid_argument("sign detector: cannot read the sign image '" + config.image_path +
                                "' (missing or not an image)");
  }
  std::vector<cv::KeyPoint> keypoints;
  cv::SIFT::create(config.max_reference_features)
      ->detectAndCompute(reference, cv::noArray(), keypoints, reference_descriptors_);
  if (static_cast<int>(keypoints.size()) < config.min_reference_features) {
    std::ostringstream message;
    message << "sign detector: the sign image '" << config.image_path
            << "' is featureless: " << keypoints.size() << " SIFT keypoints, need at least "
            << config.min_reference_features;
    throw std::invalid_argument(message.str());
  }
  // Reference pixel (u, v), centres at integers, to the sign plane: origin at the picture's
  // centre, x right, y down, metres.
  const double metres_per_px = config.width_m / reference.cols;
  height_m_ = metres_per_px * reference.rows;
  for (const cv::Point2f& p : keypointPositions(keypoints)) {
    reference_points_.emplace_back((p.x + 0.5) * metres_per_px - config.width_m / 2.0,
                                   (p.y + 0.5) * metres_per_px - height_m_ / 2.0, 0.0f);
  }
  sift_ = cv::SIFT::create(config.max_image_features);
  reference_ = reference;
}

bool SignDetector::refineHomography(const cv::Mat& gray, cv::Matx33d& plane_to_image) const {
  // Render the sign as the camera would see it under the current homography (area-sampled like
  // a sensor pixel), then align the camera image to that rendering with ECC. Aligning against a
  // picture with the same perspective and blur everywhere is what makes the refinement unbiased:
  // a fronto-parallel template biased oblique and far signs by up to 0.7 % of their range.
  const double half_w = config_.width_m / 2;
  const double half_h = height_m_ / 2;
  const std::vector<cv::Point2d> outline = {
      {-half_w, -half_h}, {half_w, -half_h}, {half_w, half_h}, {-half_w, half_h}};
  std::vector<cv::Point2d> before;
  cv::perspectiveTransform(outline, before, plane_to_image);
  const cv::Rect roi = cv::boundingRect(std::vector<cv::Point2f>(before.begin(), before.end())) &
                       cv::Rect(0, 0, gray.cols, gray.rows);
  if (roi.width < 16 || roi.height < 16) return false;

  const double area = static_cast<double>(roi.width) * roi.height;
  const int ss = area <= 40000 ? 4 : area <= 160000 ? 2 : 1;  // supersampling of the rendering
  // Source texture no finer than the supersampled view, so bilinear sampling does not alias.
  const double width_px = (cv::norm(before[1] - before[0]) + cv::norm(before[2] - before[3])) / 2;
  const int cols = std::clamp(static_cast<int>(std::lround(width_px * ss)), 16, reference_.cols);
  cv::Mat texture = reference_;
  if (cols < reference_.cols) {
    const int rows =
        std::max(16, static_cast<int>(std::lround(cols * height_m_ / config_.width_m)));
    cv::resize(reference_, texture, cv::Size(cols, rows), 0, 0, cv::INTER_AREA);
  }
  // Texture texel (u, v), centres at integers, to the sign plane; ROI pixel to the fine grid
  // (fine sample f sits at ROI pixel (f + 0.5) / ss - 0.5).
  const double mx = config_.width_m / texture.cols;
  const double my = height_m_ / texture.rows;
  const cv::Matx33d texel_to_plane(mx, 0.0, 0.5 * mx - config_.width_m / 2, 0.0, my,
                                   0.5 * my - height_m_ / 2, 0.0, 0.0, 1.0);
  const cv::Matx33d image_to_roi(1.0, 0.0, -roi.x, 0.0, 1.0, -roi.y, 0.0, 0.0, 1.0);
  const cv::Matx33d roi_to_fine(ss, 0.0, (ss - 1) / 2.0, 0.0, ss, (ss - 1) / 2.0, 0.0, 0.0, 1.0);
  cv::Mat fine, rendered;
  cv::warpPerspective(texture, fine,
                      cv::Mat(roi_to_fine * image_to_roi * plane_to_image * texel_to_plane),
                      cv::Size(roi.width * ss, roi.height * ss), cv::INTER_LINEAR,
                      cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::resize(fine, rendered, roi.size(), 0, 0, cv::INTER_AREA);
  // Only pixels well inside the sign count: within kEdgeBandPx of its outline the camera sees
  // the sign blended with an unknown background (blurred further by ECC's 5x5 Gaussian).
  cv::Mat mask = cv::Mat::zeros(roi.size(), CV_8UC1);
  std::vector<cv::Point> polygon;
  for (const cv::Point2d& p : before) {
    polygon.emplace_back(cvRound((p.x - roi.x) * 16), cvRound((p.y - roi.y) * 16));
  }
  cv::fillConvexPoly(mask, polygon, cv::Scalar(255), cv::LINE_8, 4);
  const cv::Size band(2 * kEdgeBandPx + 1, 2 * kEdgeBandPx + 1);
  cv::erode(mask, mask, cv::getStructuringElement(cv::MORPH_ELLIPSE, band));

  // ECC warp: camera ROI pixel -> rendering pixel, starting at the identity.
  cv::Mat warp = cv::Mat::eye(3, 3, CV_32F);
  double correlation = 0.0;
  try {
    correlation =
        cv::findTransformECC(gray(roi), rendered, warp, cv::MOTION_HOMOGRAPHY,
                             cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS,
                                              config_.refine_iterations, 1e-7),
                             mask, 5);
  } catch (const cv::Exception&) {
    return false;  // ECC did not converge
  }
  if (!(correlation >= config_.min_correlation)) return false;
  cv::Mat warp64;
  warp.convertTo(warp64, CV_64F);
  // rendering(S x) = camera(x) with S = roi^-1 W roi, and rendering = picture(H^-1 .), so the
  // camera sees the picture through S^-1 H.
  const cv::Matx33d image_to_rendering =
      image_to_roi.inv() * cv::Matx33d(warp64.ptr<double>()) * image_to_roi;
  cv::Matx33d refined = image_to_rendering.inv() * plane_to_image;
  refined *= 1.0 / refined(2, 2);
  std::vector<cv::Point2d> after;
  cv::perspectiveTransform(outline, after, refined);
  for (size_t i = 0; i < after.size(); ++i) {
    if (!(cv::norm(after[i] - before[i]) <= config_.max_refine_shift_px)) return false;
  }
  plane_to_image = refined;
  return true;
}

std::optional<MarkerObservation> SignDetector::detect(const cv::Mat& gray,
                                                      const CameraGeometry& camera) {
  if (gray.empty() || gray.type() != CV_8UC1) return std::nullopt;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  sift_->detectAndCompute(gray, cv::noArray(), keypoints, descriptors);
  if (static_cast<int>(keypoints.size()) < config_.min_inliers) return std::nullopt;

  std::vector<std::vector<cv::DMatch>> knn;
  matcher_.knnMatch(descriptors, reference_descriptors_, knn, 2);
  const std::vector<cv::Point2f> image_positions = keypointPositions(keypoints);
  std::vector<cv::Point3f> object_points;
  std::vector<cv::Point2f> plane_points, image_points;
  for (const std::vector<cv::DMatch>& pair : knn) {
    if (pair.size() < 2 || pair[0].distance >= config_.ratio * pair[1].distance) continue;
    const cv::Point3f& p = reference_points_[pair[0].trainIdx];
    object_points.push_back(p);
    plane_points.emplace_back(p.x, p.y);
    image_points.push_back(image_positions[pair[0].queryIdx]);
  }
  if (static_cast<int>(image_points.size()) < config_.min_inliers) return std::nullopt;

  // Homography from the sign plane (metres) to pixels; the threshold is in image pixels.
  std::vector<unsigned char> inlier_mask;
  const cv::Mat homography =
      cv::findHomography(plane_points, image_points, cv::RANSAC, config_.ransac_threshold_px,
                         inlier_mask, 2000, 0.999);
  if (homography.empty()) return std::nullopt;
  std::vector<cv::Point3f> inlier_object;
  std::vector<cv::Point2f> inlier_image;
  for (size_t i = 0; i < inlier_mask.size(); ++i) {
    if (!inlier_mask[i]) continue;
    inlier_object.push_back(object_points[i]);
    inlier_image.push_back(image_points[i]);
  }
  if (static_cast<int>(inlier_image.size()) < config_.min_inliers) return std::nullopt;

  // The sign must appear unmirrored: a homography that flips it is a false match.
  const double half_w = config_.width_m / 2.0;
  const double half_h = height_m_ / 2.0;
  const std::vector<cv::Point3f> corners3d = {{float(-half_w), float(-half_h), 0.0f},
                                              {float(half_w), float(-half_h), 0.0f},
                                              {float(half_w), float(half_h), 0.0f},
                                              {float(-half_w), float(half_h), 0.0f}};
  std::vector<cv::Point2f> corner_plane, corner_homography;
  for (const cv::Point3f& c : corners3d) corner_plane.emplace_back(c.x, c.y);
  cv::perspectiveTransform(corner_plane, corner_homography, homography);
  if (!cv::isContourConvex(corner_homography) || signedArea(corner_homography) <= 0.0) {
    return std::nullopt;
  }

  // Pose points: a grid over the sign mapped by the ECC-refined homography, or else the inlier
  // keypoints themselves. A second pass renders from the first pass's better homography.
  cv::Matx33d plane_to_image(reinterpret_cast<const double*>(homography.data));
  std::vector<cv::Point3f> pose_object = inlier_object;
  std::vector<cv::Point2f> pose_image = inlier_image;
  int passes = 0;
  while (passes < config_.refine_passes && refineHomography(gray, plane_to_image)) ++passes;
  if (passes > 0) {
    pose_object.clear();
    std::vector<cv::Point2f> grid;
    for (double fy : {-0.5, -0.25, 0.0, 0.25, 0.5}) {
      for (double fx : {-0.5, -0.25, 0.0, 0.25, 0.5}) {
        pose_object.emplace_back(fx * config_.width_m, fy * height_m_, 0.0f);
        grid.emplace_back(pose_object.back().x, pose_object.back().y);
      }
    }
    cv::perspectiveTransform(grid, pose_image, cv::Mat(plane_to_image));
  }

  // Planar pose: IPPE gives both solutions of the plane's two-fold ambiguity, best first.
  const cv::Matx33d k(camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0);
  std::vector<cv::Mat> rvecs, tvecs;
  cv::Mat errors;
  const int solutions =
      cv::solvePnPGeneric(pose_object, pose_image, k, cv::noArray(), rvecs, tvecs, false,
                          cv::SOLVEPNP_IPPE, cv::noArray(), cv::noArray(), errors);
  if (solutions < 1) return std::nullopt;
  std::vector<cv::Matx33d> rotations(solutions);
  for (int i = 0; i < solutions; ++i) cv::Rodrigues(rvecs[i], rotations[i]);
  int chosen = 0;
  if (solutions == 2 && previous_rotation_ &&
      errors.at<double>(1) - errors.at<double>(0) < config_.ambiguity_px &&
      rotationAngle(*previous_rotation_, rotations[1]) <
          rotationAngle(*previous_rotation_, rotations[0])) {
    chosen = 1;
  }
  cv::Mat rvec = rvecs[chosen].clone();
  cv::Mat tvec = tvecs[chosen].clone();
  cv::solvePnPRefineLM(pose_object, pose_image, k, cv::noArray(), rvec, tvec);

  MarkerObservation observation;
  observation.id = 0;
  cv::Rodrigues(rvec, observation.rotation);
  observation.translation = cv::Vec3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  if (!(observation.translation[2] > 0.0)) return std::nullopt;

  std::vector<cv::Point2f> reprojected;
  cv::projectPoints(inlier_object, rvec, tvec, k, cv::noArray(), reprojected);
  double squared = 0.0;
  for (size_t i = 0; i < reprojected.size(); ++i) {
    const cv::Point2f d = reprojected[i] - inlier_image[i];
    squared += d.dot(d);
  }
  observation.reprojection_error_px = std::sqrt(squared / reprojected.size());
  if (!(observation.reprojection_error_px <= config_.max_reprojection_error_px)) {
    return std::nullopt;
  }
  std::vector<cv::Point2f> corners;
  cv::projectPoints(corners3d, rvec, tvec, k, cv::noArray(), corners);
  for (size_t i = 0; i < 4; ++i) observation.corners[i] = corners[i];
  observation.quality = static_cast<double>(inlier_image.size());
  previous_rotation_ = observation.rotation;
  return observation;
}

}  // namespace follow_bot
