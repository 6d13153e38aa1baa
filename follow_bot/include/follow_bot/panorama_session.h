// A panorama capture as a caller asks for it: the request, the turn (PanoramaCapture), the
// frames grabbed, the stitch, how it ended, and when a caller waiting for it must give up.
// ROS-free; the panorama nodelet feeds it the camera frames with the robot's yaw and answers its
// ~capture calls from it. Times in s: `wall` of wall (steady) time, `now` of ROS time.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot/PanoramaDefaults.h"
#include "follow_bot/common.h"
#include "follow_bot/panorama_capture.h"
#include "follow_bot/panorama_stitch.h"
#include "follow_bot_common/config_fields.h"
#include "follow_bot_common/status_report.h"

namespace follow_bot {

// Defaults: cfg/Panorama.cfg's (PanoramaDefaults, generated).
struct PanoramaSessionConfig {
  PanoramaCaptureConfig capture;
  image_converter::MatchOptions match;
  StitchMethod method = StitchMethod::kAuto;
  double frame_timeout = PanoramaDefaults::frame_timeout;      // s, wall time: frames stopped
  double capture_timeout = PanoramaDefaults::capture_timeout;  // s, ROS time

  static constexpr auto fields() {
    using C = PanoramaSessionConfig;
    return std::make_tuple(cfgField("frame_timeout", &C::frame_timeout),
                           cfgField("capture_timeout", &C::capture_timeout));
  }
};

class PanoramaSession {
 public:
  struct Outcome {
    bool success = false;
    std::string message;
  };

  // Throws std::invalid_argument when config.capture is unusable (PanoramaCapture).
  explicit PanoramaSession(const PanoramaSessionConfig& config = PanoramaSessionConfig());

  // The robot's orientation (odometry's quaternion): its yaw is the one every frame is seen at
  // until the next. False, and ignored, unless a unit quaternion (yawOfQuaternion).
  bool orientation(double x, double y, double z, double w);
  bool hasPose() const { return yaw_.has_value(); }
  // A capture was asked for and has no outcome yet.
  bool busy() const { return pending_; }
  // A frame arrived within frame_timeout before `wall`.
  bool framesArriving(double wall) const {
    return wall - last_frame_wall_ <= config_.frame_timeout;
  }
  // Asks for a capture at `now`: the next frame with a yaw starts it.
  void request(double now);
  // One camera frame at `wall`: the turn rate (rad/s, + left) for it. Starts a requested
  // capture once there is a pose; keeps the frames to stitch.
  double update(const cv::Mat& frame, double wall);
  // The robot turns for the capture.
  bool turning() const { return capture_.active(); }
  // The last update() ended the turn: stitch() now.
  bool stitchDue() const { return stitch_due_; }
  // Stitches the grabbed frames taken by `camera` and ends the capture with the result (the
  // panorama is empty when it failed; a throwing stitcher is a failure too).
  CaptureStitch stitch(const CameraGeometry& camera);
  // For the caller waiting at `wall` and `now`: aborts a running capture when frames stopped
  // for frame_timeout, when it ran for capture_timeout or when `shutting_down`; true when it did.
  bool abortIfStalled(double wall, double now, bool shutting_down);
  // The last capture's outcome (none before the first one ended), and how many were aborted.
  const std::optional<Outcome>& last() const { return last_; }
  long aborts() const { return aborts_; }
  // For /diagnostics: ERROR "last capture failed: <why>" after a failed capture, else OK
  // "running"; state (capturing or idle), captures stopped for lost frames or time, last capture.
  StatusReport report() const;

 private:
  void end(Outcome outcome);

  PanoramaSessionConfig config_;
  PanoramaCapture capture_;
  std::optional<double> yaw_;  // rad, the last orientation's
  bool pending_ = false;       // requested, no outcome yet
  bool started_ = false;       // the turn began (a frame with a yaw came after the request)
  double requested_at_ = 0.0;
  double last_frame_wall_ = -1e9;
  bool stitch_due_ = false;
  std::vector<cv::Mat> frames_;
  std::vector<double> yaws_;
  std::optional<Outcome> last_;
  long aborts_ = 0;
};

}  // namespace follow_bot
