// Turns line measurements into velocity commands: the lecture's law, or a PD steering law with
// speed taper and a lost-line search.
//
// Conventions: the normalised error e = (centroid_x - width / 2) / (width / 2) is positive when
// the line is right of the image centre; steering right is negative angular velocity (REP-103:
// +z up, counter-clockwise positive). So a positive error always yields a negative angular.
#pragma once

#include <optional>
#include <string>

#include "follow_bot/line_detector.h"
#include "follow_bot/velocity_limiter.h"

namespace follow_bot {

enum class ControlMode {
  // The lecture, exactly: whenever the band holds any line pixel (m00 > 0), linear = 0.2 m/s
  // and angular = -error_px / 100 rad/s; confidence and min_pixels are ignored. Where the
  // lecture publishes nothing (m00 == 0) this publishes a zero twist, so a robot never keeps
  // driving on a stale command.
  kLecture,
  // PD steering on the normalised error, speed taper and the lost-line state machine.
  kPD,
};

// "lecture" / "pd" (the spelling of ROS parameters), and back.
std::optional<ControlMode> parseControlMode(const std::string& name);
const char* toString(ControlMode mode);

enum class LineState {
  kFollowing,  // the line is seen
  kLost,       // just lost: coast, turning toward the side it was last seen on
  kSearching,  // spin in place toward that side
  kGaveUp,     // stopped; any sighting resumes following
};
const char* toString(LineState state);

// Defaults suit a TurtleBot-class robot with a 640x480, 60 deg HFOV camera about 0.3 m up,
// pitched down so the detector band (3/4 of the height) sees the floor 0.5-0.8 m ahead. There
// e = 1 (image edge) is a bearing of about 30 deg (0.5 rad) to the line, so kp = 1.5 turns at
// ~3 rad/s per rad of bearing: a heading time constant of ~0.3 s, half the lecture's gain
// (320 px / 100 = 3.2 rad/s per unit e), which oscillates at higher speeds.
struct LineControllerConfig {
  ControlMode mode = ControlMode::kPD;

  // Steering (kPD): angular = -(kp * e + kd * de/dt), clamped to +-max_angular.
  double kp = 1.5;                 // rad/s per unit of normalised error
  double kd = 0.1;                 // rad/s per (unit of normalised error / s)
  double max_angular = 1.5;        // rad/s
  double max_derivative_dt = 0.5;  // s; older previous measurements give no derivative term
  // When the look-ahead band is found, e = (1 - w) e_near + w e_ahead with this w in [0, 1].
  double look_ahead_weight = 0.3;
  // Bands whose confidence is below this count as not seeing the line.
  double min_confidence = 0.2;

  // Speed (kPD): linear = max_linear * (1 - taper |e| - curvature_taper |e_ahead - e_near|),
  // clamped to [min_linear, max_linear]; the curvature term needs a found look-ahead band.
  double max_linear = 0.3;       // m/s
  double min_linear = 0.05;      // m/s
  double taper = 0.6;            // speed fraction lost per unit |e|
  double curvature_taper = 0.5;  // speed fraction lost per unit |e_ahead - e_near|

  // Lost line (kPD), timed from the last sighting.
  double lost_grace = 1.0;       // s of kLost
  double lost_linear = 0.05;     // m/s while coasting in kLost
  double lost_angular = 0.4;     // rad/s toward the last side in kLost
  double search_rate = 0.6;      // rad/s spin toward the last side in kSearching
  double search_timeout = 12.0;  // s of kSearching (~1 turn at 0.6 rad/s) before kGaveUp
};

// Empty when the configuration is usable, otherwise a message naming the first bad field,
// e.g. "kp must be >= 0, got -1".
std::string validate(const LineControllerConfig& config);

class LineController {
 public:
  // Throws std::invalid_argument with the validate() message when the configuration is unusable.
  explicit LineController(const LineControllerConfig& config = LineControllerConfig());

  // The command for one measurement. `stamp` is the frame's time in seconds (the image header
  // stamp, so the derivative uses the true interval between frames); kLecture ignores it.
  // Never returns a non-finite value. In kPD:
  //  * a non-finite stamp gives a zero twist and leaves the state alone;
  //  * a stamp earlier than the previous one (sim or bag restart) resets the controller first;
  //  * the derivative term is used only when the previous frame also saw the line and the
  //    interval is in (0, max_derivative_dt], so re-acquiring never kicks;
  //  * without a sighting the state goes kLost for lost_grace s, then kSearching for
  //    search_timeout s, then kGaveUp; a controller that has never seen the line has no side
  //    to coast toward, so it starts in kSearching (turning left) from its first update.
  Twist2D update(const LineMeasurement& measurement, double stamp);

  LineState state() const { return state_; }
  const LineControllerConfig& config() const { return config_; }

  // Forgets all history, as if newly constructed.
  void reset();

 private:
  Twist2D updateLecture(const LineMeasurement& measurement);
  Twist2D follow(const LineMeasurement& measurement, double stamp);
  Twist2D searchForLine(double stamp);

  LineControllerConfig config_;
  LineState state_ = LineState::kLost;
  bool has_stamp_ = false;
  double last_stamp_ = 0.0;
  bool seen_once_ = false;
  double outage_start_ = 0.0;  // last sighting, or the first update if none yet
  bool has_previous_error_ = false;
  double previous_error_ = 0.0;
  double previous_error_stamp_ = 0.0;
  double turn_direction_ = 1.0;  // +1 left, -1 right: toward where the line was last seen
};

}  // namespace follow_bot
