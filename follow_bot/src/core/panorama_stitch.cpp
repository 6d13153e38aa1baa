#include "follow_bot/panorama_stitch.h"

#include <cmath>
#include <cstdio>

#include "follow_bot/panorama_capture.h"
#include "image_converter/stitching.h"

namespace follow_bot {
namespace {

constexpr double kPi = 3.141592653589793;

// "" when a feature panorama `width` px wide is about as wide as the turn predicts.
std::string checkWidth(int width, const std::vector<cv::Mat>& frames,
                       const std::vector<double>& yaws, const CameraGeometry& camera) {
  const double span = std::abs(wrapAngle(yaws.front() - yaws.back()));
  const double fov = 2.0 * std::atan(frames.front().cols / (2.0 * camera.fx));
  const double expected = camera.fx * (span + fov);
  if (std::abs(width - expected) <= 0.15 * expected) return "";
  return "panorama " + std::to_string(width) + " px wide where the turn predicts " +
         std::to_string(static_cast<int>(expected)) + " px";
}

}  // namespace

CaptureStitch stitchCapture(const std::vector<cv::Mat>& frames, const std::vector<double>& yaws,
                            const CameraGeometry& camera,
                            const image_converter::MatchOptions& options, StitchMethod method) {
  if (frames.empty() || frames.size() != yaws.size()) {
    return {cv::Mat(), "stitching failed: no frames, or not one yaw per frame"};
  }
  std::string notes;
  std::string used;
  image_converter::StitchResult result;
  if (method != StitchMethod::kRotation) {
    result = image_converter::stitchMany(frames, options);
    used = "features (cv::Stitcher, " + image_converter::detectorName(options.detector) + ")";
    if (result.ok()) result.error = checkWidth(result.panorama.cols, frames, yaws, camera);
    if (!result.ok() && method == StitchMethod::kAuto) {
      notes = "; feature stitching failed (" + result.error + "), used the odometry yaws";
    }
  }
  if (method == StitchMethod::kRotation || (method == StitchMethod::kAuto && !result.ok())) {
    const image_converter::TurningCamera turning{camera.fx, camera.fy, camera.cx, camera.cy,
                                                 camera.pitch_rad};
    result = image_converter::stitchByRotation(frames, yaws, turning);
    used = "rotation (odometry yaws)";
  }
  if (!result.ok()) return {cv::Mat(), "stitching failed: " + result.error};
  const double span_deg = std::abs(wrapAngle(yaws.front() - yaws.back())) * 180.0 / kPi;
  char summary[160];
  std::snprintf(summary, sizeof summary, "%d x %d px from %zu frames over %.0f deg by ",
                result.panorama.cols, result.panorama.rows, frames.size(), span_deg);
  return {result.panorama, summary + used + notes};
}

}  // namespace follow_bot
