// Parks a unicycle robot square in front of a planar marker, from the marker's pose.
//
// Approach: ViSP's mobile-robot image-based servo (vpServo, EYEINHAND_L_cVe_eJe) on two
// features of the marker centre, its normalised image abscissa x and the depth feature
// log(Z/Z*), with the unicycle's robot Jacobian eJe and the camera mounting cVe (as ViSP's
// servoPioneerPoint2DDepth). Alone that ends at the right distance facing the marker, but
// anywhere on a circle around it. To end square and centred, the desired abscissa x* is not the
// image centre: the marker is held at a bearing b* = -k * phi (clamped to stay in view), phi
// being the robot's angle off the marker's normal, so every metre driven also turns the robot
// onto the normal (phi shrinks like distance^k). When the depth has converged but the lateral
// or heading error is still too large (a close start far off the normal), the aligning stage
// backs off to standoff + backoff with b* = +k * phi (which reduces phi while reversing) and
// the approach repeats. Close to the standoff with the lateral error within tolerance, b* = phi
// squares the heading up. Parked = position, lateral, heading and the command all within
// tolerance; a disturbance beyond twice the tolerances starts the approach again.
//
// Searching: rotate at search_rate until the marker is first seen: one full turn, then in steps
// of search_step, each followed by search_pause held still. A frame taken while turning is
// smeared (1 rad/s over a 25 ms exposure is 14 px on a 640 px, 60 deg camera): a near marker is
// still found in the first turn, a textured sign far away is not, and the steps give the
// detector still frames to look at. Steps within the view leave no bearing unseen. Lost (seen
// before, not in this frame): hold still and resume as soon as it is seen again; after lost_timeout
// without it (it left the view rather than being hidden) search again, turning toward where it was
// last.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "follow_bot/ParkerDefaults.h"
#include "follow_bot/common.h"
#include "follow_bot/marker_target.h"
#include "follow_bot_common/config_fields.h"
#include "follow_bot_common/enum_names.h"
#include "follow_bot_common/ground_projection.h"
#include "follow_bot_common/velocity_limiter.h"

namespace follow_bot {

enum class ParkingState { kSearching, kApproaching, kAligning, kParked, kLost };
inline constexpr EnumName<ParkingState> kParkingStateNames[] = {
    {ParkingState::kSearching, "searching"},
    {ParkingState::kApproaching, "approaching"},
    {ParkingState::kAligning, "aligning"},
    {ParkingState::kParked, "parked"},
    {ParkingState::kLost, "lost"}};
inline const char* toString(ParkingState state) { return nameIn(kParkingStateNames, state); }

struct ParkingServoConfig {
  using D = ParkerDefaults;  // cfg/Parker.cfg's defaults (generated)
  static constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;
  double standoff_m = D::standoff;    // base origin to marker centre along its normal, m
  double gain = D::gain;              // vpServo lambda, 1/s
  double steer_gain = D::steer_gain;  // k in b* = -k * phi
  double max_bearing_rad =
      D::max_bearing_deg * kRadPerDeg;  // |b*| bound, keeps the marker inside the 60 deg view
  double backoff_m = D::backoff;        // aligning: reverse to standoff + backoff, m
  double max_linear = D::max_linear;    // m/s, both components scaled down together beyond it
  double max_angular = D::max_angular;  // rad/s, likewise
  double search_rate = D::search_rate;  // rad/s; the first search turns this way (positive: left)
  double search_step_rad = D::search_step_deg * kRadPerDeg;  // turned between pauses
  double search_pause = D::search_pause;  // s still after each step (0: turns without stopping)
  double lost_timeout = D::lost_timeout;  // s a lost marker is waited for before searching again
  double position_tolerance = D::position_tolerance;  // m, along the normal
  double lateral_tolerance = D::lateral_tolerance;    // m, across the normal
  double heading_tolerance_rad = D::heading_tolerance_deg * kRadPerDeg;
  double linear_tolerance = 0.01;   // m/s, commanded speed to count as stopped
  double angular_tolerance = 0.02;  // rad/s
  CameraGeometry camera;            // mounting (height, pitch, x offset) for cVe and the base frame

  static constexpr auto fields() {
    using C = ParkingServoConfig;
    return std::make_tuple(
        cfgField("standoff_m", &C::standoff_m, positive(), "standoff"),
        cfgField("gain", &C::gain, positive()),
        cfgField("steer_gain", &C::steer_gain, atLeast(1.0)),
        cfgField("max_bearing_rad", &C::max_bearing_rad, inRange(0.0, 0.5), "max_bearing_deg",
                 kRadPerDeg),
        cfgField("backoff_m", &C::backoff_m, positive(), "backoff"),
        cfgField("max_linear", &C::max_linear, positive()),
        cfgField("max_angular", &C::max_angular, positive()),
        cfgField("search_rate", &C::search_rate, inRange(-3.2, 3.2)),
        cfgField("search_step_rad", &C::search_step_rad, positive(), "search_step_deg", kRadPerDeg),
        cfgField("search_pause", &C::search_pause, atLeast(0.0)),
        cfgField("lost_timeout", &C::lost_timeout, atLeast(0.0)),
        cfgField("position_tolerance", &C::position_tolerance, positive()),
        cfgField("lateral_tolerance", &C::lateral_tolerance, positive()),
        cfgField("heading_tolerance_rad", &C::heading_tolerance_rad, positive(),
                 "heading_tolerance_deg", kRadPerDeg),
        field("linear_tolerance", &C::linear_tolerance, positive()),
        field("angular_tolerance", &C::angular_tolerance, positive()));
  }
};

std::string validate(const ParkingServoConfig& config);

// The marker's pose as the robot needs it, in base_link (REP-103, metres and radians).
// along: robot origin to marker centre along the marker's outward normal.
// lateral: robot origin off the normal, positive to the marker's left (the robot's right when
//   square). heading: the rotation (positive left) that would make the robot face the marker
//   squarely. phi: the robot's angle off the normal seen from the marker, atan2(lateral, along).
// bearing: the marker centre's bearing from the robot, positive left.
struct ParkingError {
  double along = 0;
  double lateral = 0;
  double heading = 0;
  double phi = 0;
  double bearing = 0;
};

// A marker seen from the camera (its pose in the optical frame) placed in base_link.
struct MarkerInBase {
  cv::Vec3d centre;
  cv::Vec3d outward_normal;  // unit, out of the marker's face (toward a viewer in front)
};
MarkerInBase markerInBase(const MarkerObservation& marker, const CameraGeometry& camera);

// The parking error for a marker pose in the camera optical frame.
ParkingError parkingError(const MarkerObservation& marker, const CameraGeometry& camera);

class ParkingServo {
 public:
  explicit ParkingServo(const ParkingServoConfig& config);  // throws std::invalid_argument
  ~ParkingServo();
  ParkingServo(const ParkingServo&) = delete;
  ParkingServo& operator=(const ParkingServo&) = delete;

  // One frame at `time_s`: the marker if seen. Returns the desired command (before the node's
  // limiter).
  Twist2D update(const std::optional<MarkerObservation>& marker, double time_s);

  // Takes the intrinsics (fx, fy, cx, cy) of `camera`, as from CameraInfo; the mounting stays.
  void setIntrinsics(const CameraGeometry& camera);

  ParkingState state() const { return state_; }
  const std::optional<ParkingError>& lastError() const { return last_error_; }
  const ParkingServoConfig& config() const { return config_; }

 private:
  Twist2D servo(const MarkerObservation& marker, double depth_goal, double bearing_goal);
  Twist2D search(double time_s);
  bool withinTolerance(const ParkingError& error, double scale) const;

  struct Impl;
  ParkingServoConfig config_;
  std::unique_ptr<Impl> impl_;
  ParkingState state_ = ParkingState::kSearching;
  bool seen_ = false;
  double last_seen_s_ = 0.0;
  double search_direction_ = 1.0;           // sign applied to |search_rate|
  std::optional<double> search_started_s_;  // while searching
  std::optional<ParkingError> last_error_;
};

}  // namespace follow_bot
