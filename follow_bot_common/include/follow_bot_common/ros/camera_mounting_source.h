// Where a behaviour's camera is mounted: from tf (the robot description, the default) or from
// the mounting ~params (readCameraMounting), the same for every behaviour.
//
// ~params (read here, once, for every behaviour node):
//  * ~camera_mounting (tf | params, default tf): tf looks up ~base_frame <- the image's
//    header.frame_id for every frame (a non-blocking lookup of the latest transform, so a
//    changed description is followed); params uses ~camera_height, ~camera_pitch_deg and
//    ~camera_x_offset as they are.
//  * ~base_frame (default base_link): the robot frame the ground points are in. Its height above
//    the floor is its height above base_footprint (REP 120) when tf knows base_footprint, else 0
//    (base_frame itself is on the floor).
//  * ~mounting_timeout (s, > 0, default 5): with tf, how long the first frames wait for the
//    transform before the mounting ~params are used instead (logged loudly, once). A transform
//    that appears later still replaces them.
// With tf, the behaviours of one process (nodelets in one manager) share one tf2 buffer and
// listener per pair of tf topics their node handles resolve (/tf, /tf_static, or remapped).
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include <ros/node_handle.h>

#include "follow_bot_common/ground_projection.h"

namespace follow_bot_common {

struct SharedTfListener;  // a tf2 buffer and its listener, shared within the process

class CameraMountingSource {
 public:
  // The floor frame of REP 120, for base_frame's height above the floor.
  static constexpr const char* kFootprintFrame = "base_footprint";

  // Reads the ~params above from `pnh`; `fallback` is the mounting the ~params give. Throws
  // std::invalid_argument naming a bad ~param. `name` prefixes the log messages.
  CameraMountingSource(ros::NodeHandle& nh, const ros::NodeHandle& pnh, CameraGeometry fallback,
                       std::string name);

  // The mounting for a frame from the camera frame `frame_id`: writes it into `camera` (the
  // intrinsics untouched) and returns true once known; false while waiting for tf. `changed`:
  // the mounting in `camera` differs from before. The mounting is logged when first known and
  // whenever it changes.
  bool update(const std::string& frame_id, CameraGeometry& camera, bool& changed);

  const std::string& baseFrame() const { return base_frame_; }

 private:
  // The mounting from tf, or empty with `why` set.
  std::optional<CameraGeometry> fromTf(const std::string& frame_id, const CameraGeometry& camera,
                                       std::string& why);
  void use(const CameraGeometry& mounting, const std::string& source, CameraGeometry& camera,
           bool& changed);

  const std::string name_;
  bool use_tf_ = true;
  std::string base_frame_;
  double timeout_s_ = 0.0;
  CameraGeometry fallback_;
  std::shared_ptr<SharedTfListener> tf_;  // the process's for this node's tf topics
  std::optional<std::chrono::steady_clock::time_point> waiting_since_;
  bool known_ = false;
  bool from_tf_ = false;
};

}  // namespace follow_bot_common
