// The follower's steering laws behind one interface: a camera frame's line measurement in, a
// velocity command out. Three laws (SteeringMode), one configuration (SteeringConfig) with one
// set of limits, one factory (makeSteeringLaw). The laws are in line_controller.h (lecture, pd
// and the lost-line search) and line_path.h (path).
//
// Conventions: the normalised error e = (centroid_x - width / 2) / (width / 2) is positive when
// the line is right of the image centre; steering right is negative angular velocity (REP-103:
// +z up, counter-clockwise positive). So a positive error always yields a negative angular.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "follow_bot/common.h"
#include "follow_bot/line_detector.h"
#include "follow_bot_common/config_fields.h"
#include "follow_bot_common/enum_names.h"
#include "follow_bot_common/ground_projection.h"
#include "follow_bot_common/velocity_limiter.h"

namespace follow_bot {

enum class SteeringMode {
  // The lecture, exactly: whenever the band holds any line pixel (m00 > 0), linear = 0.2 m/s
  // and angular = -error_px / 100 rad/s; confidence and min_pixels are ignored. Where the
  // lecture publishes nothing (m00 == 0) this publishes a zero twist, so a robot never keeps
  // driving on a stale command.
  kLecture,
  // PD steering on the normalised error, speed taper and the lost-line search.
  kPD,
  // Tracks the remembered line at the robot base; pd (with its search) once the memory runs out.
  kPath,
};

// The values of the follower's ~mode.
inline constexpr EnumName<SteeringMode> kSteeringModeNames[] = {
    {SteeringMode::kLecture, "lecture"}, {SteeringMode::kPD, "pd"}, {SteeringMode::kPath, "path"}};
inline std::optional<SteeringMode> parseSteeringMode(std::string_view name) {
  return valueIn(kSteeringModeNames, name);
}
inline const char* toString(SteeringMode mode) { return nameIn(kSteeringModeNames, mode); }

enum class LineState {
  kFollowing,  // the line is seen
  kLost,       // just lost: coast, turning toward the side it was last seen on
  kSearching,  // spin in place toward that side
  kGaveUp,     // stopped; any sighting resumes following
};
inline constexpr EnumName<LineState> kLineStateNames[] = {{LineState::kFollowing, "following"},
                                                          {LineState::kLost, "lost"},
                                                          {LineState::kSearching, "searching"},
                                                          {LineState::kGaveUp, "gave_up"}};
inline const char* toString(LineState state) { return nameIn(kLineStateNames, state); }

// pd's steering and speed taper.
struct PdConfig {
  // angular = -(kp * e + kd * de/dt), clamped to +-max_angular.
  double kp = FollowerDefaults::kp;  // rad/s per unit of normalised error
  double kd = FollowerDefaults::kd;  // rad/s per (unit of normalised error / s)
  double max_derivative_dt = 0.5;    // s; older previous measurements give no derivative term
  // When the look-ahead band is found, e = (1 - w) e_near + w e_ahead with this w in [0, 1].
  double look_ahead_weight = FollowerDefaults::look_ahead_weight;
  // linear = max_linear * (1 - taper |e| - curvature_taper |e_ahead - e_near|), clamped to
  // [min_linear, max_linear]; the curvature term needs a found look-ahead band.
  double taper = FollowerDefaults::taper;                      // speed fraction lost per unit |e|
  double curvature_taper = FollowerDefaults::curvature_taper;  // per unit |e_ahead - e_near|

  static constexpr auto fields() {
    using C = PdConfig;
    return std::make_tuple(cfgField("kp", &C::kp, atLeast(0.0)),
                           cfgField("kd", &C::kd, atLeast(0.0)),
                           field("max_derivative_dt", &C::max_derivative_dt, positive()),
                           cfgField("look_ahead_weight", &C::look_ahead_weight, inRange(0.0, 1.0)),
                           cfgField("taper", &C::taper, atLeast(0.0)),
                           cfgField("curvature_taper", &C::curvature_taper, atLeast(0.0)));
  }
};

// The lost-line search (pd's, and so path's once its memory runs out), timed from the last
// sighting.
struct LineSearchConfig {
  double lost_grace = 1.0;                             // s of kLost
  double lost_linear = 0.05;                           // m/s while coasting in kLost
  double lost_angular = 0.4;                           // rad/s toward the last side in kLost
  double search_rate = FollowerDefaults::search_rate;  // rad/s spin toward the last side
  double search_timeout = 12.0;  // s of kSearching (~1 turn at 0.6 rad/s) before kGaveUp

  static constexpr auto fields() {
    using C = LineSearchConfig;
    return std::make_tuple(field("lost_grace", &C::lost_grace, atLeast(0.0)),
                           field("lost_linear", &C::lost_linear, atLeast(0.0)),
                           field("lost_angular", &C::lost_angular, atLeast(0.0)),
                           cfgField("search_rate", &C::search_rate, atLeast(0.0)),
                           field("search_timeout", &C::search_timeout, atLeast(0.0)));
  }
};

// path's tracking law and line memory; the law itself is described in line_path.h.
struct PathConfig {
  // Steering gains of the distance-parametrised law. heading_gain^2 = 4 lateral_gain is
  // critical damping, here a double pole at heading_gain / 2 = 10 per metre: an offset d0
  // decays as d0 (1 + 10 s) exp(-10 s), to 20 % after 0.3 m and 4 % after 0.5 m without
  // overshoot; a heading error peaks as an offset after 0.1 m. Stiffer gains barely help (the
  // remaining error comes from the curvature fit and dead reckoning) but amplify detector noise
  // and the one-frame lag (2.3 cm of travel per frame at 0.7 m/s and 30 Hz).
  double heading_gain = FollowerDefaults::heading_gain;  // 1/m per unit sin(theta_e)
  double lateral_gain = FollowerDefaults::lateral_gain;  // 1/m^2: curvature per metre of e_y

  // m of path fitted around the base (offset, heading, curvature). Longer is steadier (the
  // curvature's noise falls as fit_length^-2.5 at a given point spacing) but smooths a sudden
  // change of curvature over more travel.
  double fit_length = 0.2;
  // m the fit may be extended past the remembered points. Before the start of the path, pure
  // pursuit hands over to the fit linearly over this distance.
  double max_extrapolation = 0.1;
  double start_lookahead = 0.3;      // m; until the path reaches the base, aim at a point this far
  double keep_behind = 0.2;          // m; points further behind the base are forgotten
  double max_point_age = 10.0;       // s; older points are forgotten (odometry drifts)
  int max_points = 1000;             // oldest points are forgotten beyond this count
  double min_point_spacing = 0.002;  // m; closer sightings in the same band are not stored
  // m; a jump at least this long between successive sightings of the near band is a stretch
  // of line the camera never saw (the end of a curve tighter than the nearest floor it sees,
  // a gap in the paint): the remembered path bridges it with a curve (line_path.h). Shorter
  // jumps are within the fit's reach.
  double bridge_gap = 0.1;
  // s; a longer interval between frames makes the dead reckoning too uncertain, so the memory
  // is cleared.
  double max_frame_gap = 0.5;
  // s from the frame to the base executing the command made from it (a real base's 50-150 ms
  // actuation delay). The law steers from where the commands already sent will have taken the
  // robot by then (line_path.h); 0 steers from where the frame was taken.
  double command_latency = FollowerDefaults::command_latency;

  static constexpr auto fields() {
    using C = PathConfig;
    return std::make_tuple(cfgField("heading_gain", &C::heading_gain, atLeast(0.0)),
                           cfgField("lateral_gain", &C::lateral_gain, atLeast(0.0)),
                           field("fit_length", &C::fit_length, positive()),
                           field("max_extrapolation", &C::max_extrapolation, atLeast(0.0)),
                           field("start_lookahead", &C::start_lookahead, positive()),
                           field("keep_behind", &C::keep_behind, atLeast(0.0)),
                           field("max_point_age", &C::max_point_age, positive()),
                           field("max_points", &C::max_points, atLeast(3)),
                           field("min_point_spacing", &C::min_point_spacing, atLeast(0.0)),
                           field("bridge_gap", &C::bridge_gap, positive()),
                           field("max_frame_gap", &C::max_frame_gap, positive()),
                           cfgField("command_latency", &C::command_latency, inRange(0.0, 1.0)));
  }
};

// Defaults suit a TurtleBot-class robot with a 640x480, 60 deg HFOV camera about 0.3 m up,
// pitched down 20 deg; the detector band sees the floor ~0.46 m ahead (band_distance). There
// e = 1 (image edge) is a bearing of about 30 deg (0.5 rad) to the line, so kp = 1.5 turns at
// ~3 rad/s per rad of bearing: a heading time constant of ~0.3 s, half the lecture's gain
// (320 px / 100 = 3.2 rad/s per unit e), which oscillates at higher speeds.
struct SteeringConfig {
  SteeringMode mode = *parseSteeringMode(FollowerDefaults::mode);

  // Limits of pd and path (the lecture's law has the lecture's constants). path slows below
  // max_linear (not below min_linear) so that its arc needs at most max_angular.
  double max_linear = FollowerDefaults::max_linear;    // m/s, top speed
  double min_linear = FollowerDefaults::min_linear;    // m/s, speed floor while following
  double max_angular = FollowerDefaults::max_angular;  // rad/s
  // Bands whose detector confidence is below this count as not seeing the line (pd and path).
  double min_confidence = 0.2;

  PdConfig pd;
  LineSearchConfig search;
  PathConfig path;

  static constexpr auto fields() {
    using C = SteeringConfig;
    return std::make_tuple(cfgField("max_linear", &C::max_linear, positive()),
                           cfgField("min_linear", &C::min_linear, atLeast(0.0)),
                           cfgField("max_angular", &C::max_angular, positive()),
                           field("min_confidence", &C::min_confidence, inRange(0.0, 1.0)));
  }
};

// Empty when the configuration is usable (every section, whatever the mode), otherwise a
// message naming the first bad field, e.g. "kp must be >= 0, got -1".
std::string validate(const SteeringConfig& config);

// One camera frame as a steering law sees it.
struct LineObservation {
  LineMeasurement measurement;
  // s, the frame's time (the image header stamp), so the derivative and the search's timeouts
  // use the true interval between frames. The lecture ignores it.
  double stamp = 0.0;
  // The robot's motion since the previous frame as a twist held over the interval (exact arc):
  // the command actually sent (after any limiter), or a twist from wheel odometry where that is
  // better. Only path uses it (to carry its line memory).
  Twist2D applied;
  // The command sent to the base after the previous frame (after any limiter), held until this
  // frame. Only path uses it: the commands of the last command_latency s are still to be
  // executed. Zero (a caller that does not say) predicts no motion.
  Twist2D sent;
  // s, the base's frame-to-motion delay as measured (LatencyEstimator); empty: the configured
  // path.command_latency.
  std::optional<double> latency;
};

class SteeringLaw {
 public:
  virtual ~SteeringLaw() = default;

  // The command for one frame. Never returns a non-finite value. Every law but the lecture's:
  //  * a non-finite stamp gives a zero twist and leaves the state alone;
  //  * a stamp earlier than the previous one (sim or bag restart) resets the law first.
  virtual Twist2D step(const LineObservation& frame) = 0;
  virtual LineState state() const = 0;
  // Forgets all history, as if newly made.
  virtual void reset() = 0;
  virtual SteeringMode mode() const = 0;
};

// The law config.mode names. path needs the camera's intrinsics and mounting; without `camera`
// (no camera_info yet) path mode gets the pd law on the same settings, which is path's own
// fallback. Throws std::invalid_argument with the validate() message when the configuration
// (or, for path, the camera) is unusable.
std::unique_ptr<SteeringLaw> makeSteeringLaw(const SteeringConfig& config,
                                             const std::optional<CameraGeometry>& camera);

}  // namespace follow_bot
