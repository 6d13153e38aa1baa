#include "follow_bot_common/ros/intrinsics_source.h"

#include <algorithm>
#include <optional>
#include <string>
#include <utility>

#include <image_geometry/pinhole_camera_model.h>
#include <sensor_msgs/distortion_models.h>

#include "follow_bot_common/image_frame.h"

namespace follow_bot_common {

namespace {

// How many distortion coefficients a CameraInfo distortion_model takes (0: a model OpenCV's
// undistortPoints cannot apply).
size_t distortionSize(const std::string& model) {
  if (model == sensor_msgs::distortion_models::PLUMB_BOB) return 5;
  if (model == sensor_msgs::distortion_models::RATIONAL_POLYNOMIAL) return 8;
  return 0;
}

std::string sizeText(const cv::Size& size) {
  return std::to_string(size.width) + "x" + std::to_string(size.height);
}

// Both zero (not given) or both a frame's: a size no frame can have is a broken camera_info.
std::string calibratedSizeError(const sensor_msgs::CameraInfo& info) {
  const bool unset = info.width == 0 && info.height == 0;
  const bool frame_size = info.width > 0 && info.width <= kMaxDimension && info.height > 0 &&
                          info.height <= kMaxDimension;
  if (unset || frame_size) return "";
  return "its size " + std::to_string(info.width) + "x" + std::to_string(info.height) +
         " is no frame's (1-" + std::to_string(kMaxDimension) + " each, or both 0)";
}

}  // namespace

// The rectified camera from P (K when P is all zero, an uncalibrated P).
std::string updateIntrinsics(const sensor_msgs::CameraInfo& info, bool image_rectified,
                             CameraGeometry& camera) {
  image_geometry::PinholeCameraModel model;
  model.fromCameraInfo(info);
  const cv::Matx33d k = model.fullIntrinsicMatrix();
  const cv::Matx34d p = model.fullProjectionMatrix();
  const bool p_unset = p == cv::Matx34d::zeros();
  CameraGeometry updated = camera;
  updated.fx = p_unset ? k(0, 0) : p(0, 0);
  updated.fy = p_unset ? k(1, 1) : p(1, 1);
  updated.cx = p_unset ? k(0, 2) : p(0, 2);
  updated.cy = p_unset ? k(1, 2) : p(1, 2);
  updated.lens.reset();
  const bool distorted = std::any_of(info.D.begin(), info.D.end(), [](double d) { return d != 0; });
  if (!image_rectified && distorted) {
    const size_t size = distortionSize(info.distortion_model);
    if (size == 0) {
      return "distortion_model '" + info.distortion_model +
             "' is not supported (plumb_bob, rational_polynomial), or send rectified frames";
    }
    if (info.D.size() != size) {
      return "D of a " + info.distortion_model + " lens must have " + std::to_string(size) +
             " coefficients, got " + std::to_string(info.D.size());
    }
    updated.lens = CameraLens{k, info.D, model.rotationMatrix()};
  }
  std::string error = validate(updated);
  if (!error.empty()) return error;
  camera = updated;
  return "";
}

IntrinsicsSource::IntrinsicsSource(bool image_rectified, std::string topic)
    : image_rectified_(image_rectified), topic_(std::move(topic)) {}

IntrinsicsSource::Update IntrinsicsSource::take(const sensor_msgs::CameraInfo& info,
                                                CameraGeometry& camera) {
  Update update;
  CameraGeometry calibrated = camera;
  update.error = calibratedSizeError(info);
  if (update.error.empty()) update.error = updateIntrinsics(info, image_rectified_, calibrated);
  if (!update.error.empty()) return update;
  calibrated_ = calibrated;
  calibrated_size_ = cv::Size(static_cast<int>(info.width), static_cast<int>(info.height));
  calibration_pending_ = true;
  fit(frame_size_.empty() ? calibrated_size_ : frame_size_, camera, update);
  return update;
}

IntrinsicsSource::Update IntrinsicsSource::forFrame(const cv::Size& size, CameraGeometry& camera) {
  Update update;
  const bool in_force = has_intrinsics_ && (intrinsics_size_.empty() || size == intrinsics_size_);
  const bool fitted_already = !calibration_pending_ && (in_force || !has_intrinsics_);
  if (!fitted_already && !fit(size, camera, update)) {
    const std::string described = topic_ + " is for " + sizeText(calibrated_size_);
    if (in_force) {
      update.warning = described + ", not frames of " + sizeText(size) +
                       ": keeping the intrinsics of the last one that was";
    } else {
      update.error =
          "the frame is " + sizeText(size) + " but " + described + ", not an image of that shape";
    }
  }
  if (update.error.empty()) frame_size_ = size;
  return update;
}

// The intrinsics last taken, made those of frames of `size`, into `camera`; false, `camera`
// unchanged, when such frames are not their image resized.
bool IntrinsicsSource::fit(const cv::Size& size, CameraGeometry& camera, Update& update) {
  const std::optional<CameraGeometry> fitted =
      intrinsicsForFrame(calibrated_, calibrated_size_, size);
  if (!fitted) return false;
  update.fitted = true;
  update.changed = !has_intrinsics_ || !sameIntrinsics(*fitted, camera);
  camera.fx = fitted->fx;
  camera.fy = fitted->fy;
  camera.cx = fitted->cx;
  camera.cy = fitted->cy;
  camera.lens = fitted->lens;
  has_intrinsics_ = true;
  intrinsics_size_ = calibrated_size_.empty() ? cv::Size() : size;  // empty: any size
  calibration_pending_ = false;
  return true;
}

}  // namespace follow_bot_common
