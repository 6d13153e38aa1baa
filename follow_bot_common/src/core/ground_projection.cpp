#include "follow_bot_common/ground_projection.h"

#include <cmath>
#include <sstream>

#include "follow_bot_common/config_checks.h"

namespace follow_bot {
namespace {

constexpr double kMaxPitchRad = 89.0 * 3.14159265358979323846 / 180.0;

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
  return "";
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

}  // namespace follow_bot
