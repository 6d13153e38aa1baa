// The turn-in-place schedule of a panorama capture: which way to turn on each frame and when
// to grab it. ROS-free; the panorama nodelet feeds it the robot's yaw once per camera frame.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "follow_bot/PanoramaDefaults.h"
#include "follow_bot/common.h"
#include "follow_bot_common/config_fields.h"

namespace follow_bot {

// Defaults: cfg/Panorama.cfg's (PanoramaDefaults, generated), in radians.
struct PanoramaCaptureConfig {
  using Defaults = PanoramaDefaults;
  static constexpr double kRadPerDeg = 3.141592653589793 / 180.0;
  double total_angle = Defaults::total_angle_deg * kRadPerDeg;  // rad swept, centred on the start
  double step_angle = Defaults::step_angle_deg * kRadPerDeg;  // rad between grabbed frames, at most
  double max_turn_rate = Defaults::max_angular;  // rad/s while turning to the next heading
  double min_turn_rate = Defaults::min_angular;  // rad/s, so the end of a turn does not creep
  double yaw_gain = Defaults::yaw_gain;          // 1/s: turn rate per radian of heading error
  double yaw_tolerance =
      Defaults::yaw_tolerance_deg * kRadPerDeg;  // rad: close enough to a heading
  int settle_frames = Defaults::settle_frames;   // frames held still at a heading before grabbing
  bool return_to_start = Defaults::return_to_start;  // turn back to the start heading at the end

  // The angles' and rates' ranges are linked to each other: validate() checks them.
  static constexpr auto fields() {
    using C = PanoramaCaptureConfig;
    return std::make_tuple(
        cfgField("total_angle", &C::total_angle, {}, "total_angle_deg", kRadPerDeg),
        cfgField("step_angle", &C::step_angle, {}, "step_angle_deg", kRadPerDeg),
        cfgField("max_turn_rate", &C::max_turn_rate, positive(), "max_angular"),
        cfgField("min_turn_rate", &C::min_turn_rate, {}, "min_angular"),
        cfgField("yaw_gain", &C::yaw_gain, positive()),
        cfgField("yaw_tolerance", &C::yaw_tolerance, {}, "yaw_tolerance_deg", kRadPerDeg),
        cfgField("settle_frames", &C::settle_frames, atLeast(0)),
        cfgField("return_to_start", &C::return_to_start));
  }
};

// Empty when the configuration is usable, otherwise a message naming the first bad field.
std::string validate(const PanoramaCaptureConfig& config);

// Angle wrapped into (-pi, pi].
double wrapAngle(double angle);

// The heading (rotation about z, rad) of an orientation quaternion; NaN unless it is a unit
// quaternion (norm within 1e-3 of 1). A garbage or uninitialised pose still gives a finite
// atan2, which would be a wrong heading.
double yawOfQuaternion(double x, double y, double z, double w);

class PanoramaCapture {
 public:
  // What to do with the current frame.
  struct Step {
    double angular = 0.0;   // rad/s, + turns left (counter-clockwise)
    bool grab = false;      // keep this frame (and the yaw it was taken at)
    bool finished = false;  // the capture is over (all frames grabbed, back at the start)
  };

  // Throws std::invalid_argument with the validate() message when the configuration is unusable.
  explicit PanoramaCapture(const PanoramaCaptureConfig& config = PanoramaCaptureConfig());

  // Plans the headings from the left end of the sweep to the right end, around `start_yaw`.
  void start(double start_yaw);
  // The command for the frame seen at `yaw` (rad, same reference as start_yaw).
  Step update(double yaw);
  void abort() { active_ = false; }

  bool active() const { return active_; }
  // Headings (rad, absolute) at which frames are grabbed, left to right.
  const std::vector<double>& headings() const { return headings_; }
  std::size_t grabbed() const { return next_heading_; }
  const PanoramaCaptureConfig& config() const { return config_; }

 private:
  double turnRateToward(double target, double yaw) const;

  PanoramaCaptureConfig config_;
  std::vector<double> headings_;
  double start_yaw_ = 0.0;
  std::size_t next_heading_ = 0;
  int still_frames_ = 0;
  bool active_ = false;
};

}  // namespace follow_bot
