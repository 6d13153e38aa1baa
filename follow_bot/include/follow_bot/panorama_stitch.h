// The end of a panorama capture: the frames grabbed at their odometry yaws, stitched by features
// or by the known rotation, with the check that a feature panorama is as wide as the turn says.
// ROS-free; the panorama nodelet publishes what it returns.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot/common.h"
#include "follow_bot_common/enum_names.h"
#include "follow_bot_common/ground_projection.h"
#include "image_converter/feature_matching.h"

namespace follow_bot {

// auto: features, else the odometry yaws; features: cv::Stitcher only; rotation: yaws only.
enum class StitchMethod { kAuto, kFeatures, kRotation };

inline constexpr EnumName<StitchMethod> kStitchMethodNames[] = {
    {StitchMethod::kAuto, "auto"},
    {StitchMethod::kFeatures, "features"},
    {StitchMethod::kRotation, "rotation"}};
// "auto", "features" or "rotation"; empty for any other name.
inline std::optional<StitchMethod> parseStitchMethod(std::string_view name) {
  return valueIn(kStitchMethodNames, name);
}

struct CaptureStitch {
  cv::Mat panorama;     // empty when stitching failed
  std::string message;  // "W x H px from N frames over A deg by <method>[; notes]", or why not
  bool ok() const { return !panorama.empty(); }
};

// Stitches `frames` (left to right) grabbed at `yaws` (rad, one per frame) by a camera with
// `camera`'s intrinsics and pitch. A feature panorama whose width is more than 15 % off
// fx * (yaw span + field of view) links look-alike views wrongly and counts as failed.
CaptureStitch stitchCapture(const std::vector<cv::Mat>& frames, const std::vector<double>& yaws,
                            const CameraGeometry& camera,
                            const image_converter::MatchOptions& options, StitchMethod method);

}  // namespace follow_bot
