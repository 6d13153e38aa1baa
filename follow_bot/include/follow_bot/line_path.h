// Follows a floor line with the robot's base rather than with the camera band.
//
// The band sees the floor about half a metre ahead, so any law that steers on the band error
// alone cuts corners. PathLaw (SteeringMode::kPath) instead remembers where the line was seen,
// carried along in the robot frame by the commands actually sent (dead reckoning), and tracks
// that remembered path at base_link with curvature feed-forward:
//
//   curvature command c = kappa + heading_gain * sin(theta_e) + lateral_gain * e_y   (1/m)
//   angular = linear * c
//
// where e_y, theta_e and kappa are the path's lateral offset, relative heading and curvature at
// the foot of the base on the path. Linearised about the path, with d = -e_y the robot's
// offset: d'' + heading_gain d' + lateral_gain d = 0 in distance travelled (' = d/ds),
// independent of speed.
//
// A sighting is the band's line centre on the floor (floorCentre: the line's edges in the rows
// of whole runs, fitted on the floor), not the ground point of its centroid: where a curve
// enters or leaves the view the image's side edge cuts the line's patch, whose centroid then
// lies up to half a line width off the line, and the bridges below extrapolate the fitted
// heading from there (on a camera whose band sees the floor 1 m ahead the headings came out
// 11-32 deg wrong, and the robot ran 16 cm off the line); and a far band sees a curve across
// many columns, where the centroid of the curved patch lies mm inside the curve.
//
// Where the camera never saw the line (its nearest floor lies beyond the end of a tight curve,
// or the paint has a gap) successive sightings of the band jump by bridge_gap or more. The end
// of the stretch before the jump is then remembered with its heading and curvature (fitted
// when that end was seen, with the fitted window's curvature), and every frame the jump is
// bridged by two arcs: that stretch's own curve continued, then the arc that meets the first
// sighting past the jump along the heading fitted to the sightings there (a single arc while
// they are too few for a heading). A curve that ends unseen and runs into a
// straight or another curve is bridged exactly. The law tracks the bridge like any remembered
// stretch.
//
// A base executes a command a latency after the frame it was made from (its actuation delay:
// measured from odometry by LatencyEstimator where the caller has it, else command_latency), and
// in the meantime still executes the commands sent in the latency before the frame. The law
// therefore steers from the pose those commands will have taken the robot to: it replays the
// last latency of commands sent (frame.sent) from the base and evaluates the fit
// and pure pursuit there. Steering from the frame's own pose instead acts on an offset a latency
// old: at 0.5 m/s a 150 ms delay is 7.5 cm of travel, most of the law's 10 cm time constant,
// and the robot weaves.
//
// Direction of travel: while the path steers, the direction it runs is remembered (carried by
// the motion like the points). Once the memory has run out, the fallback searching, a sighting
// is taken as the line only when the line there, followed away from the robot, runs within
// 90 deg of that direction: a search that spun the robot round must not take the line it came
// along for the way on. The direction is forgotten after max_point_age s, like the points.
//
// The remembered path is only as good as the dead reckoning: exact when the robot executes the
// commands it is sent (as the harness simulator does), but a robot turning 5 % more or less
// than commanded runs about 1 cm off a 0.6 m radius curve.
#pragma once

#include <deque>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot/common.h"
#include "follow_bot/line_controller.h"
#include "follow_bot/path_geometry.h"
#include "follow_bot/steering_law.h"
#include "follow_bot_common/ground_projection.h"

namespace follow_bot {

// Uses config.path, the limits and min_confidence; its fallback is a PdLaw on the same config.
// Speed: linear = max_linear, lowered (not below min_linear) so that |linear * c| <=
// max_angular: on a sharp curve or a big correction the robot slows down and still drives the
// arc it computed; only below min_linear is the angular clamped instead.
class PathLaw : public SteeringLaw {
 public:
  // The remembered path at the base, where the commands in flight will have taken it (the pose
  // the law steers from), for a debug topic.
  struct PathState {
    bool valid = false;      // the path reaches the base and the tracking law is in use
    double lateral = 0.0;    // e_y, m: distance to the path, positive when it lies to the left
    double heading = 0.0;    // theta_e, rad: path direction relative to the robot, + = left
    double curvature = 0.0;  // kappa, 1/m: positive when the path turns left
    int points = 0;          // points remembered
  };

  // Throws std::invalid_argument when the configuration or the camera is unusable;
  // config.mode is not looked at.
  PathLaw(const SteeringConfig& config, const CameraGeometry& camera);

  // Besides SteeringLaw's rules:
  //  * frame.applied carries the memory; a non-finite motion, or a gap over max_frame_gap,
  //    clears it;
  //  * until the remembered path reaches the base (start-up, re-acquisition) the robot drives
  //    the arc tangent to its heading through the remembered point start_lookahead away
  //    (pure pursuit), which on a circle or straight started on the line is the line itself;
  //  * when no path point remains ahead, the memory is cleared and the pd fallback steers; it
  //    has been shown the last sighting up to then, so its lost-line search is timed from the
  //    end of the remembered path and turns toward the side the line was last seen on.
  //  * frame.sent, held over the last frame.latency s of frames (command_latency when the
  //    frame has none), places the pose it steers from;
  //  * with the memory run out, a band whose line runs against the remembered direction of
  //    travel, or whose direction is unmeasurable, counts as not seeing the line.
  Twist2D step(const LineObservation& frame) override;

  // kFollowing while the remembered path steers, otherwise the fallback's state.
  LineState state() const override;
  // Forgets everything, as if newly constructed.
  void reset() override;
  SteeringMode mode() const override { return SteeringMode::kPath; }

  const PathState& pathState() const { return path_state_; }
  // Remembered line points in base_link (x forward, y left, metres), oldest first.
  std::vector<cv::Point2d> pathPoints() const;

 private:
  struct PathPoint {
    cv::Point2d position;  // base_link at the latest frame
    double stamp = 0.0;    // frame it was seen in
    bool look_ahead = false;
  };

  // The end of a remembered stretch where a jump of bridge_gap or more begins, in base_link.
  struct BridgeStart {
    cv::Point2d position;
    cv::Point2d tangent;     // unit, the direction the path runs
    double curvature = 0.0;  // 1/m, + = left
    double stamp = 0.0;      // frame it was seen in
    double end_stamp = 0.0;  // frame of the first sighting past the jump
  };

  // A command sent over [begin, end) s.
  struct SentCommand {
    double begin = 0.0;
    double end = 0.0;
    Twist2D twist;
  };

  void moveMemory(const Twist2D& applied, double dt);
  void recordSent(const Twist2D& sent, double dt, double stamp, double latency);
  // Whether a band's sighting may be taken as the line (the direction of travel rule).
  bool keepsDirection(const BandMeasurement& band, double stamp) const;
  // Remembers where a jump from `before` (the band's previous sighting) to `after` begins,
  // when it is a jump forward along a stretch whose heading and curvature fit.
  void startBridge(const PathPoint& before, const cv::Point2d& after, double stamp);
  // The direction and curvature at the band's sighting `end`, fitted on its remembered points
  // up to it (and the bridges before it); empty when too few.
  std::optional<BridgeStart> stretchEnd(const PathPoint& end);
  // Appends samples of the curves across the remembered jumps, and forgets the jumps whose
  // sightings past them are all forgotten.
  void appendBridges(std::vector<cv::Point2d>& positions, std::vector<double>& stamps);
  void forgetStalePoints(double stamp);
  // Remembers the sightings kept by the direction of travel rule; returns the measurement with
  // the bands it refused marked not found.
  LineMeasurement remember(const LineMeasurement& measurement, double stamp);
  // Stores the band's floorCentre() unless it has none or it repeats the band's latest.
  void rememberBand(const BandMeasurement& band, bool look_ahead, double stamp);
  Twist2D drive(double curvature) const;

  SteeringConfig config_;
  CameraGeometry camera_;
  PdLaw fallback_;
  std::deque<PathPoint> points_;
  std::deque<BridgeStart> bridges_;  // oldest first
  // stretchEnd() at the band's latest sighting, fitted when it was seen and carried by the
  // motion: a jump found later bridges from this, not from the few points left of the stretch
  // by then (those further behind the base than keep_behind are forgotten, and a curve fitted
  // on the last few centimetres is skewed).
  std::optional<BridgeStart> stretch_end_;
  PathState path_state_;
  bool following_ = false;
  bool has_stamp_ = false;
  double last_stamp_ = 0.0;
  LineMeasurement last_sighting_;  // shown to the fallback while the path steers
  std::deque<SentCommand> sent_;   // oldest first, the last latency s
  // Unit, base_link: the way the remembered path ran when it last steered.
  std::optional<cv::Point2d> travel_direction_;
  double travel_stamp_ = 0.0;
};

}  // namespace follow_bot
