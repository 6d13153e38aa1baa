// Follows a floor line with the robot's base rather than with the camera band.
//
// The band sees the floor about half a metre ahead, so any law that steers on the band error
// alone cuts corners. LinePathFollower instead remembers where the line was seen, carried along
// in the robot frame by the commands actually sent (dead reckoning), and tracks that remembered
// path at base_link with curvature feed-forward:
//
//   curvature command c = kappa + heading_gain * sin(theta_e) + lateral_gain * e_y   (1/m)
//   angular = linear * c
//
// where e_y, theta_e and kappa are the path's lateral offset, relative heading and curvature at
// the foot of the base on the path. Linearised about the path, with d = -e_y the robot's
// offset: d'' + heading_gain d' + lateral_gain d = 0 in distance travelled (' = d/ds),
// independent of speed.
//
// The remembered path is only as good as the dead reckoning: exact when the robot executes the
// commands it is sent (as the harness simulator does), but a robot turning 5 % more or less
// than commanded runs about 1 cm off a 0.6 m radius curve.
#pragma once

#include <deque>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot/ground_projection.h"
#include "follow_bot/line_controller.h"
#include "follow_bot/line_detector.h"
#include "follow_bot/velocity_limiter.h"

namespace follow_bot {

struct LinePathConfig {
  // Speed. linear = speed, lowered (not below min_speed) so that |linear * c| <= max_angular:
  // on a sharp curve or a big correction the robot slows down and still drives the arc it
  // computed; only below min_speed is the angular clamped instead.
  double speed = 0.3;        // m/s
  double min_speed = 0.05;   // m/s
  double max_angular = 1.5;  // rad/s, |angular| bound

  // Steering gains of the distance-parametrised law above. heading_gain^2 = 4 lateral_gain is
  // critical damping, here a double pole at heading_gain / 2 = 10 per metre: an offset d0
  // decays as d0 (1 + 10 s) exp(-10 s), to 20 % after 0.3 m and 4 % after 0.5 m without
  // overshoot; a heading error peaks as an offset after 0.1 m. Stiffer gains barely help (the
  // remaining error comes from the curvature fit and dead reckoning) but amplify detector noise
  // and the one-frame lag (2.3 cm of travel per frame at 0.7 m/s and 30 Hz).
  double heading_gain = 20.0;   // 1/m per unit sin(theta_e)
  double lateral_gain = 100.0;  // 1/m^2: curvature per metre of e_y

  // Bands below this detector confidence are not remembered.
  double min_confidence = 0.2;

  // Path memory and fit.
  // m of path fitted around the base (offset, heading, curvature). Longer is steadier (the
  // curvature's noise falls as fit_length^-2.5 at a given point spacing) but smooths a sudden
  // change of curvature over more travel.
  double fit_length = 0.2;
  // m the fit may be extended past the remembered points. Before the start of the path, pure
  // pursuit (below) hands over to the fit linearly over this distance.
  double max_extrapolation = 0.1;
  double start_lookahead = 0.3;      // m; until the path reaches the base, aim at a point this far
  double keep_behind = 0.2;          // m; points further behind the base are forgotten
  double max_point_age = 10.0;       // s; older points are forgotten (odometry drifts)
  int max_points = 1000;             // oldest points are forgotten beyond this count
  double min_point_spacing = 0.002;  // m; closer sightings in the same band are not stored
  // s; a longer interval between frames makes the dead reckoning too uncertain, so the memory
  // is cleared.
  double max_frame_gap = 0.5;
};

// Empty when the configuration is usable, otherwise a message naming the first bad field.
std::string validate(const LinePathConfig& config);

class LinePathFollower {
 public:
  // The remembered path at the base, for a debug topic.
  struct PathState {
    bool valid = false;      // the path reaches the base and the tracking law is in use
    double lateral = 0.0;    // e_y, m: distance to the path, positive when it lies to the left
    double heading = 0.0;    // theta_e, rad: path direction relative to the robot, + = left
    double curvature = 0.0;  // kappa, 1/m: positive when the path turns left
    int points = 0;          // points remembered
  };

  // `fallback` configures the LineController that takes over once the remembered path has run
  // out; it always runs in ControlMode::kPD (the mode with the lost-line search), whatever
  // fallback.mode says. Throws std::invalid_argument when any of the three is unusable.
  LinePathFollower(const LinePathConfig& config, const CameraGeometry& camera,
                   const LineControllerConfig& fallback);

  // The command for one camera frame. `stamp` is the frame's time in seconds and
  // `applied_since_last_frame` the robot's motion since the previous frame as a twist held over
  // the interval (exact arc): the command actually sent (after any limiter), or a twist from
  // wheel odometry where that is better. Never returns a non-finite value:
  //  * a non-finite stamp gives a zero twist and changes nothing;
  //  * a stamp earlier than the previous one (sim or bag restart) resets everything first;
  //  * a non-finite motion, or a gap over max_frame_gap, clears the path memory;
  //  * until the remembered path reaches the base (start-up, re-acquisition) the robot drives
  //    the arc tangent to its heading through the remembered point start_lookahead away
  //    (pure pursuit), which on a circle or straight started on the line is the line itself;
  //  * when no path point remains ahead, the memory is cleared and the fallback controller
  //    steers; it has been shown the last sighting up to then, so its kLost -> kSearching ->
  //    kGaveUp sequence is timed from the end of the remembered path and turns toward the side
  //    the line was last seen on.
  Twist2D update(const LineMeasurement& measurement, double stamp,
                 const Twist2D& applied_since_last_frame);

  // kFollowing while the remembered path steers, otherwise the fallback's state.
  LineState state() const;
  const PathState& pathState() const { return path_state_; }
  // Remembered line points in base_link (x forward, y left, metres), oldest first.
  std::vector<cv::Point2d> pathPoints() const;

  // Forgets everything, as if newly constructed.
  void reset();

 private:
  struct PathPoint {
    cv::Point2d position;  // base_link at the latest frame
    double stamp = 0.0;    // frame it was seen in
    bool look_ahead = false;
  };

  void moveMemory(const Twist2D& applied, double dt);
  void forgetStalePoints(double stamp);
  void remember(const LineMeasurement& measurement, double stamp);
  // Stores the band's ground point unless it repeats the band's latest; false when the
  // centroid has no ground point.
  bool rememberBand(const BandMeasurement& band, bool look_ahead, double stamp);
  Twist2D drive(double curvature) const;

  LinePathConfig config_;
  CameraGeometry camera_;
  LineController fallback_;
  std::deque<PathPoint> points_;
  PathState path_state_;
  bool following_ = false;
  bool has_stamp_ = false;
  double last_stamp_ = 0.0;
  LineMeasurement last_sighting_;  // shown to the fallback while the path steers
};

}  // namespace follow_bot
