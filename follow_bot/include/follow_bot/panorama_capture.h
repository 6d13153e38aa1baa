// The turn-in-place schedule of a panorama capture: which way to turn on each frame and when
// to grab it. ROS-free; the panorama nodelet feeds it the robot's yaw once per camera frame.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace follow_bot {

struct PanoramaCaptureConfig {
  double total_angle = 2.0943951023931953;  // rad (120 deg) swept, centred on the start heading
  double step_angle = 0.3490658503988659;   // rad (20 deg) between grabbed frames, at most
  double max_turn_rate = 0.5;               // rad/s while turning to the next heading
  double min_turn_rate = 0.05;              // rad/s, so the last bit of a turn does not creep
  double yaw_gain = 2.0;                    // 1/s: turn rate per radian of heading error
  double yaw_tolerance = 0.01;              // rad: close enough to a heading to stop there
  int settle_frames = 5;                    // frames held still at a heading before grabbing
  bool return_to_start = true;              // turn back to the start heading at the end
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
