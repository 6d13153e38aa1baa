#include "image_converter/stitching.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>
#include <opencv2/stitching.hpp>
#include <opencv2/stitching/detail/blenders.hpp>
#include <opencv2/stitching/detail/warpers.hpp>

#include "channels.h"

namespace image_converter {
namespace {

std::string sizeError(const cv::Size& size) {
  if (size.width <= 0 || size.height <= 0 || size.width > kMaxPanoramaSide ||
      size.height > kMaxPanoramaSide) {
    return "the panorama would be " + std::to_string(size.width) + " x " +
           std::to_string(size.height) + " px: the views do not form a plausible panorama";
  }
  return "";
}

std::string stitcherStatusText(cv::Stitcher::Status status) {
  switch (status) {
    case cv::Stitcher::ERR_NEED_MORE_IMGS:
      return "cv::Stitcher found too few overlapping images";
    case cv::Stitcher::ERR_HOMOGRAPHY_EST_FAIL:
      return "cv::Stitcher could not estimate the homographies";
    case cv::Stitcher::ERR_CAMERA_PARAMS_ADJUST_FAIL:
      return "cv::Stitcher could not adjust the camera parameters";
    default:
      return "cv::Stitcher failed with status " + std::to_string(static_cast<int>(status));
  }
}

// Optical axes (columns) expressed in the robot base frame (x forward, y left, z up) for a camera
// looking forward, tilted down by `pitch`; the optical frame is x right, y down, z forward.
cv::Matx33d baseToOptical(double pitch) {
  const cv::Vec3d z_axis(std::cos(pitch), 0.0, -std::sin(pitch));
  const cv::Vec3d x_axis(0.0, -1.0, 0.0);
  const cv::Vec3d y_axis = z_axis.cross(x_axis);
  return cv::Matx33d(x_axis[0], y_axis[0], z_axis[0], x_axis[1], y_axis[1], z_axis[1], x_axis[2],
                     y_axis[2], z_axis[2]);
}

cv::Matx33d rotationAboutZ(double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return cv::Matx33d(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
}

}  // namespace

StitchResult stitchPair(const cv::Mat& a, const cv::Mat& b, const MatchOptions& options) {
  StitchResult result;
  const PairMatch match = matchPair(a, b, options);
  result.pairs.push_back(match);
  if (!match.ok()) {
    result.error = match.error;
    return result;
  }

  // Bounding box of A and of B mapped into A's frame; an integer shift keeps A's pixels exact.
  std::vector<cv::Point2d> corners;
  for (const cv::Size& size : {a.size(), b.size()}) {
    const bool is_b = corners.size() == 4;
    for (const cv::Point2d& corner :
         {cv::Point2d(0, 0), cv::Point2d(size.width, 0), cv::Point2d(size.width, size.height),
          cv::Point2d(0, size.height)}) {
      corners.push_back(is_b ? applyHomography(match.homography, corner) : corner);
    }
  }
  double min_x = 0, min_y = 0, max_x = 0, max_y = 0;
  for (const cv::Point2d& p : corners) {
    min_x = std::min(min_x, p.x);
    min_y = std::min(min_y, p.y);
    max_x = std::max(max_x, p.x);
    max_y = std::max(max_y, p.y);
  }
  min_x = std::floor(min_x);
  min_y = std::floor(min_y);
  const cv::Size size(static_cast<int>(std::min(std::ceil(max_x - min_x), 1e9)),
                      static_cast<int>(std::min(std::ceil(max_y - min_y), 1e9)));
  result.error = sizeError(size);
  if (!result.ok()) return result;

  const cv::Matx33d shift(1, 0, -min_x, 0, 1, -min_y, 0, 0, 1);
  const cv::Matx33d b_to_panorama = shift * match.homography;
  cv::Mat warped_a, warped_b, mask_a, mask_b;
  cv::warpPerspective(withChannels(a, 3), warped_a, shift, size, cv::INTER_LINEAR,
                      cv::BORDER_CONSTANT);
  cv::warpPerspective(withChannels(b, 3), warped_b, b_to_panorama, size, cv::INTER_LINEAR,
                      cv::BORDER_CONSTANT);
  // A pixel belongs to a view only where its interpolation read no border: the warped full
  // mask is exactly 255 there.
  cv::warpPerspective(cv::Mat(a.size(), CV_8U, cv::Scalar(255)), mask_a, shift, size,
                      cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::warpPerspective(cv::Mat(b.size(), CV_8U, cv::Scalar(255)), mask_b, b_to_panorama, size,
                      cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  mask_a = mask_a == 255;
  mask_b = mask_b == 255;

  const int overlap = cv::countNonZero(mask_a & mask_b);
  const double smaller_area = std::min(a.total(), b.total());
  if (overlap < 0.02 * smaller_area) {
    result.error = "the images overlap by only " + std::to_string(overlap) + " px";
    return result;
  }

  // Feathered seam: each view's weight is its distance to its own border, so the overlap fades
  // smoothly from one view to the other instead of switching at a visible line.
  cv::Mat weight_a, weight_b;
  cv::distanceTransform(mask_a, weight_a, cv::DIST_L2, 3);
  cv::distanceTransform(mask_b, weight_b, cv::DIST_L2, 3);
  cv::Mat float_a, float_b;
  warped_a.convertTo(float_a, CV_32FC3);
  warped_b.convertTo(float_b, CV_32FC3);
  cv::Mat weight_sum = weight_a + weight_b;
  cv::Mat blended(size, CV_32FC3, cv::Scalar::all(0));
  for (int row = 0; row < size.height; ++row) {
    const float* wa = weight_a.ptr<float>(row);
    const float* wb = weight_b.ptr<float>(row);
    const float* ws = weight_sum.ptr<float>(row);
    const cv::Vec3f* pa = float_a.ptr<cv::Vec3f>(row);
    const cv::Vec3f* pb = float_b.ptr<cv::Vec3f>(row);
    cv::Vec3f* out = blended.ptr<cv::Vec3f>(row);
    for (int col = 0; col < size.width; ++col) {
      if (ws[col] > 0.0f) out[col] = (wa[col] * pa[col] + wb[col] * pb[col]) / ws[col];
    }
  }
  blended.convertTo(result.panorama, CV_8UC3);
  result.origin_of_first = cv::Point2d(-min_x, -min_y);
  return result;
}

StitchResult stitchMany(const std::vector<cv::Mat>& images, const MatchOptions& options) {
  StitchResult result;
  if (images.size() < 2) {
    result.error = "need at least two images, got " + std::to_string(images.size());
    return result;
  }
  result.error = validate(options);
  for (std::size_t i = 0; i < images.size() && result.ok(); ++i) {
    result.error = checkImage(images[i], "image " + std::to_string(i + 1), options.min_contrast);
  }
  if (!result.ok()) return result;
  // cv::Stitcher silently drops views it cannot join; checking each consecutive pair first
  // names the pair that breaks the chain.
  for (std::size_t i = 0; i + 1 < images.size(); ++i) {
    result.pairs.push_back(matchPair(images[i], images[i + 1], options));
    if (!result.pairs.back().ok()) {
      result.error = "images " + std::to_string(i + 1) + " and " + std::to_string(i + 2) + ": " +
                     result.pairs.back().error;
      return result;
    }
  }

  std::vector<cv::Mat> bgr;
  bgr.reserve(images.size());
  for (const cv::Mat& image : images) bgr.push_back(withChannels(image, 3));
  const cv::Ptr<cv::Stitcher> stitcher = cv::Stitcher::create(cv::Stitcher::PANORAMA);
  stitcher->setFeaturesFinder(createDetector(options));
  cv::Mat panorama;
  const cv::Stitcher::Status status = stitcher->stitch(bgr, panorama);
  if (status != cv::Stitcher::OK) {
    result.error = stitcherStatusText(status);
    return result;
  }
  if (stitcher->component().size() != images.size()) {
    result.error = "cv::Stitcher joined only " + std::to_string(stitcher->component().size()) +
                   " of the " + std::to_string(images.size()) + " images";
    return result;
  }
  result.error = sizeError(panorama.size());
  if (result.ok()) result.panorama = panorama;
  return result;
}

std::string validate(const TurningCamera& camera) {
  if (!(std::isfinite(camera.fx) && camera.fx > 0.0)) return "fx must be > 0";
  if (!(std::isfinite(camera.fy) && camera.fy > 0.0)) return "fy must be > 0";
  if (!std::isfinite(camera.cx) || !std::isfinite(camera.cy)) return "cx, cy must be finite";
  if (!(std::abs(camera.pitch) < 1.5)) return "pitch must be within +-1.5 rad";
  return "";
}

StitchResult stitchByRotation(const std::vector<cv::Mat>& images, const std::vector<double>& yaws,
                              const TurningCamera& camera) {
  StitchResult result;
  if (images.size() < 2) {
    result.error = "need at least two images, got " + std::to_string(images.size());
    return result;
  }
  if (yaws.size() != images.size()) {
    result.error = "got " + std::to_string(yaws.size()) + " yaws for " +
                   std::to_string(images.size()) + " images";
    return result;
  }
  result.error = validate(camera);
  for (std::size_t i = 0; i < images.size() && result.ok(); ++i) {
    result.error =
        checkImage(images[i], "image " + std::to_string(i + 1), MatchOptions().min_contrast);
    if (result.ok() && !std::isfinite(yaws[i])) {
      result.error = "yaw " + std::to_string(i + 1) + " is not finite";
    }
  }
  if (!result.ok()) return result;

  // Panorama frame: the optical frame of a level camera at the middle yaw, so the cylinder axis
  // is the true vertical and the panorama is centred on the swept span.
  const auto [min_yaw, max_yaw] = std::minmax_element(yaws.begin(), yaws.end());
  const double reference_yaw = 0.5 * (*min_yaw + *max_yaw);
  const cv::Matx33d level = baseToOptical(0.0);
  const cv::Matx33d mounted = baseToOptical(camera.pitch);
  const cv::Matx33f intrinsics(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);

  cv::detail::CylindricalWarper warper(static_cast<float>(camera.fx));
  std::vector<cv::Mat> warped(images.size()), masks(images.size());
  std::vector<cv::Point> corners(images.size());
  std::vector<cv::Size> sizes(images.size());
  for (std::size_t i = 0; i < images.size(); ++i) {
    // Camera rays to panorama-frame rays: optical -> base -> turned by the relative yaw -> level.
    const cv::Matx33f rotation(level.t() * rotationAboutZ(yaws[i] - reference_yaw) * mounted);
    cv::Mat warped_bgr;
    corners[i] = warper.warp(withChannels(images[i], 3), cv::Mat(intrinsics), cv::Mat(rotation),
                             cv::INTER_LINEAR, cv::BORDER_REFLECT, warped_bgr);
    warper.warp(cv::Mat(images[i].size(), CV_8U, cv::Scalar(255)), cv::Mat(intrinsics),
                cv::Mat(rotation), cv::INTER_NEAREST, cv::BORDER_CONSTANT, masks[i]);
    warped_bgr.convertTo(warped[i], CV_16SC3);
    sizes[i] = warped[i].size();
  }
  const cv::Rect extent = cv::detail::resultRoi(corners, sizes);
  result.error = sizeError(extent.size());
  if (!result.ok()) return result;

  cv::detail::FeatherBlender blender;
  blender.prepare(extent);
  for (std::size_t i = 0; i < images.size(); ++i) blender.feed(warped[i], masks[i], corners[i]);
  cv::Mat blended, blended_mask;
  blender.blend(blended, blended_mask);
  blended.convertTo(result.panorama, CV_8UC3);
  return result;
}

}  // namespace image_converter
