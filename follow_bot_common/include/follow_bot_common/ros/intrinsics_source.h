// A behaviour's camera intrinsics: from its camera_info stream, fitted to the frames that arrive.
//
// A camera_info is read through image_geometry's PinholeCameraModel (updateIntrinsics): the
// rectified camera P and, unless the frames are rectified already (image_rect), the lens K, D, R
// whose distortion the cores undo on the pixels they use. Its intrinsics are those of images of
// its width and height; a frame that is that image resized by one factor (binning, a resized
// stream, a new camera_info not there yet) gets them scaled (intrinsicsForFrame). A camera_info
// that does not describe the frames leaves the intrinsics in force when they do; a frame that
// neither describes cannot be used.
//
// No ROS communication: the behaviour's nodelet feeds it the messages and logs what it says.
#pragma once

#include <string>

#include <sensor_msgs/CameraInfo.h>
#include <opencv2/core.hpp>

#include "follow_bot_common/ground_projection.h"

namespace follow_bot_common {

// The intrinsics side of `camera` from `info` (the lens only for raw frames, `image_rectified`
// false, through a lens with distortion). "" on success, else why the message was ignored
// (`camera` unchanged).
std::string updateIntrinsics(const sensor_msgs::CameraInfo& info, bool image_rectified,
                             CameraGeometry& camera);

class IntrinsicsSource {
 public:
  // What a camera_info or a frame did to the camera's intrinsics.
  struct Update {
    std::string error;     // why the message or frame cannot be used ("": it can)
    std::string warning;   // a camera_info ignored while the intrinsics in force still hold
    bool fitted = false;   // intrinsics were written into the camera just now
    bool changed = false;  // ... and they are the first, or differ from those before
  };

  // `image_rectified`: the frames are rectified, a camera_info's D is not applied. `topic`:
  // camera_info's resolved name, for the messages.
  IntrinsicsSource(bool image_rectified, std::string topic);

  // A camera_info. A usable one is taken, and its intrinsics go into `camera` at once when it
  // describes the frames arriving (or none came yet); else the next frame decides.
  Update take(const sensor_msgs::CameraInfo& info, CameraGeometry& camera);
  // Before a frame of `size` is used: fits the intrinsics taken to it when they are not yet.
  // No error while no camera_info has come (the camera's defaults are used).
  Update forFrame(const cv::Size& size, CameraGeometry& camera);

  bool known() const { return has_intrinsics_; }  // the camera holds a camera_info's intrinsics

 private:
  bool fit(const cv::Size& size, CameraGeometry& camera, Update& update);

  const bool image_rectified_;
  const std::string topic_;
  bool has_intrinsics_ = false;
  cv::Size intrinsics_size_;          // the frame size they are for (empty: any)
  CameraGeometry calibrated_;         // intrinsics as the last usable camera_info gave them
  cv::Size calibrated_size_;          // its width and height (empty: not given)
  bool calibration_pending_ = false;  // calibrated_ is not in the camera yet
  cv::Size frame_size_;               // the last usable frame's
};

}  // namespace follow_bot_common
