// Stitching views into one image: two views by their homography with a feathered seam, N views
// through OpenCV's cv::Stitcher, and views of a camera turning in place by its known rotation.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "image_converter/feature_matching.h"

namespace image_converter {

struct StitchResult {
  std::string error;  // empty on success; the panorama is then non-empty
  cv::Mat panorama;   // BGR8
  // Where image A's (the first image's) pixel (0, 0) landed in the panorama (two-view stitch).
  cv::Point2d origin_of_first;
  std::vector<PairMatch> pairs;  // matches between consecutive images, when features were used
  bool ok() const { return error.empty(); }
};

// Largest panorama side accepted, so a bad homography cannot allocate gigabytes.
constexpr int kMaxPanoramaSide = 20000;

// Warps B into A's frame by matchPair's homography and blends the overlap with weights that
// fall off towards each image's border (a feathered seam). Fails on a bad match or an overlap
// below 2 % of the smaller image.
StitchResult stitchPair(const cv::Mat& a, const cv::Mat& b, const MatchOptions& options);

// Stitches images (left to right, each overlapping the next) with cv::Stitcher in panorama mode
// (spherical warp, bundle adjustment, multi-band blending). Fails unless every image joins the
// panorama. `pairs` holds matchPair's result for each consecutive pair, for reporting.
StitchResult stitchMany(const std::vector<cv::Mat>& images, const MatchOptions& options);

// A pinhole camera turned about the vertical axis through its optical centre.
struct TurningCamera {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;  // intrinsics in pixels
  double pitch = 0.0;  // rad, positive tilts the optical axis down from horizontal
};

// Empty when usable, otherwise a message naming the first bad field.
std::string validate(const TurningCamera& camera);

// Stitches views taken by `camera` at the given yaws (rad, counter-clockwise seen from above,
// any reference) without features: each view is projected on a cylinder about the vertical axis
// (cv::detail::CylindricalWarper, focal fx) by its known rotation and the views are feathered.
// Left of the panorama is the most counter-clockwise direction. The panorama is
// fx * (yaw span + horizontal field of view) pixels wide.
StitchResult stitchByRotation(const std::vector<cv::Mat>& images, const std::vector<double>& yaws,
                              const TurningCamera& camera);

}  // namespace image_converter
