#include "follow_bot_common/ground_projection.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>

#include <opencv2/calib3d.hpp>

#include "follow_bot_common/config_checks.h"

namespace follow_bot_common {
namespace {

constexpr double kMaxPitchRad = 89.0 * 3.14159265358979323846 / 180.0;

// The distortion vector lengths cv::undistortPoints accepts (plumb_bob: 5, rational_polynomial: 8).
bool usableDistortionSize(size_t size) {
  return size == 4 || size == 5 || size == 8 || size == 12 || size == 14;
}

std::string validateLens(const CameraLens& lens) {
  const cv::Matx33d& k = lens.camera_matrix;
  for (const std::string& error : {
           requirePositive("lens K fx", k(0, 0)),
           requirePositive("lens K fy", k(1, 1)),
           requireFinite("lens K cx", k(0, 2)),
           requireFinite("lens K cy", k(1, 2)),
       }) {
    if (!error.empty()) return error;
  }
  if (!usableDistortionSize(lens.distortion.size())) {
    return "lens D must have 4, 5, 8, 12 or 14 coefficients, got " +
           std::to_string(lens.distortion.size());
  }
  if (!std::all_of(lens.distortion.begin(), lens.distortion.end(),
                   [](double d) { return std::isfinite(d); })) {
    return "lens D must be finite";
  }
  // R rotates the raw camera into the rectified one: orthonormal with determinant 1.
  const cv::Matx33d& r = lens.rectification;
  const double off_identity = cv::norm(r * r.t() - cv::Matx33d::eye(), cv::NORM_INF);
  if (!(off_identity < 1e-6) || !(std::abs(cv::determinant(r) - 1.0) < 1e-6)) {
    return "lens R must be a rotation matrix";
  }
  return "";
}

}  // namespace

std::string validate(const CameraGeometry& camera) {
  for (const std::string& error : {
           requirePositive("fx", camera.fx),
           requirePositive("fy", camera.fy),
           requireFinite("cx", camera.cx),
           requireFinite("cy", camera.cy),
           requirePositive("height_m", camera.height_m),
           requireFinite("x_offset_m", camera.x_offset_m),
       }) {
    if (!error.empty()) return error;
  }
  // At +-90 deg the image-down axis becomes horizontal and the horizon leaves the image model.
  if (!(std::abs(camera.pitch_rad) < kMaxPitchRad)) {
    std::ostringstream message;
    message << "pitch_rad must be within +-89 deg, got " << camera.pitch_rad;
    return message.str();
  }
  return camera.lens ? validateLens(*camera.lens) : "";
}

bool sameIntrinsics(const CameraGeometry& a, const CameraGeometry& b) {
  const bool same_lens = a.lens && b.lens ? a.lens->camera_matrix == b.lens->camera_matrix &&
                                                a.lens->distortion == b.lens->distortion &&
                                                a.lens->rectification == b.lens->rectification
                                          : !a.lens && !b.lens;
  return a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy && same_lens;
}

std::optional<CameraGeometry> intrinsicsForFrame(const CameraGeometry& camera,
                                                 const cv::Size& calibrated,
                                                 const cv::Size& frame) {
  if (calibrated.empty() || frame == calibrated) return camera;
  // Integer sizes: one factor for both axes exactly, or the pixels are not square to each other.
  if (static_cast<int64_t>(frame.width) * calibrated.height !=
      static_cast<int64_t>(frame.height) * calibrated.width) {
    return std::nullopt;
  }
  const double scale = static_cast<double>(frame.width) / calibrated.width;
  CameraGeometry scaled = camera;
  scaled.fx *= scale;
  scaled.fy *= scale;
  scaled.cx *= scale;
  scaled.cy *= scale;
  if (scaled.lens) {
    cv::Matx33d& k = scaled.lens->camera_matrix;
    for (int row = 0; row < 2; ++row) {
      for (int col = 0; col < 3; ++col) k(row, col) *= scale;
    }
  }
  return scaled;
}

namespace {

template <typename Point>
std::vector<Point> undistorted(const CameraGeometry& camera, const std::vector<Point>& raw) {
  if (!camera.lens || raw.empty()) return raw;
  const CameraLens& lens = *camera.lens;
  const cv::Matx33d rectified(camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0);
  std::vector<Point> rectified_pixels;
  cv::undistortPoints(
      raw, rectified_pixels, lens.camera_matrix, lens.distortion, lens.rectification, rectified,
      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
  return rectified_pixels;
}

}  // namespace

std::vector<cv::Point2d> rectifyPixels(const CameraGeometry& camera,
                                       const std::vector<cv::Point2d>& raw) {
  return undistorted(camera, raw);
}

std::vector<cv::Point2f> rectifyPixels(const CameraGeometry& camera,
                                       const std::vector<cv::Point2f>& raw) {
  return undistorted(camera, raw);
}

cv::Point2d rectifyPixel(const CameraGeometry& camera, const cv::Point2d& raw) {
  if (!camera.lens) return raw;
  return rectifyPixels(camera, std::vector<cv::Point2d>{raw}).front();
}

std::optional<cv::Point2d> pixelToGround(const CameraGeometry& camera, double u, double v) {
  // The ray (a, b, 1) in the optical frame is a * x_c + b * y_c + z_c in base_link, with
  // x_c = (0, -1, 0), y_c = (-sin p, 0, -cos p) and z_c = (cos p, 0, -sin p).
  const double a = (u - camera.cx) / camera.fx;
  const double b = (v - camera.cy) / camera.fy;
  const double sin_p = std::sin(camera.pitch_rad);
  const double cos_p = std::cos(camera.pitch_rad);
  const double descent = sin_p + b * cos_p;        // -z of the ray: > 0 when it heads for the floor
  if (!(descent > 0.0)) return std::nullopt;       // also rejects NaN
  const double range = camera.height_m / descent;  // ray parameter at z = 0
  const cv::Point2d ground(camera.x_offset_m + range * (cos_p - b * sin_p), -range * a);
  if (!std::isfinite(ground.x) || !std::isfinite(ground.y)) return std::nullopt;
  return ground;
}

}  // namespace follow_bot_common
