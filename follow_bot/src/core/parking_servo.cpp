#include "follow_bot/parking_servo.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpVelocityTwistMatrix.h>
#include <visp3/visual_features/vpFeatureDepth.h>
#include <visp3/visual_features/vpFeaturePoint.h>
#include <visp3/vs/vpServo.h>

#include "follow_bot/common.h"
#include "follow_bot_common/config_checks.h"

namespace follow_bot {

namespace {

// Depth within this of the goal counts as arrived for the stage switches (m).
constexpr double kArrived = 0.02;

// Columns: the optical frame's x (right), y (down), z (forward) in base_link, for a camera
// pitched down by `pitch` (ground_projection.h).
cv::Matx33d cameraToBase(double pitch) {
  const double c = std::cos(pitch);
  const double s = std::sin(pitch);
  return cv::Matx33d(0, -s, c,  //
                     -1, 0, 0,  //
                     0, -c, -s);
}

double clampAbs(double value, double bound) { return std::max(-bound, std::min(bound, value)); }

// The largest marker bearing that keeps all its corners in view with a margin: half the
// horizontal field of view less the marker's own angular half-width, less 3 deg.
double bearingInView(const MarkerObservation& marker, const CameraGeometry& camera) {
  const double half_fov = std::atan2(camera.cx, camera.fx);
  const double centre = std::atan2(marker.translation[0], marker.translation[2]);
  double half_width = 0.0;
  for (const cv::Point2d& corner : marker.corners) {
    half_width =
        std::max(half_width, std::abs(std::atan2(corner.x - camera.cx, camera.fx) - centre));
  }
  return std::max(0.0, half_fov - half_width - 6.0 * M_PI / 180.0);
}

}  // namespace

std::string validate(const ParkingServoConfig& config) {
  for (const std::string& error : {
           checkFields(config),
           validate(config.camera),
       }) {
    if (!error.empty()) return error;
  }
  if (config.standoff_m - config.camera.x_offset_m <= 0.05) {
    return "standoff_m must leave the marker > 5 cm in front of the camera";
  }
  return "";
}

MarkerInBase markerInBase(const MarkerObservation& marker, const CameraGeometry& camera) {
  const cv::Matx33d base_from_camera = cameraToBase(camera.pitch_rad);
  const cv::Vec3d into_marker =
      base_from_camera *
      cv::Vec3d(marker.rotation(0, 2), marker.rotation(1, 2), marker.rotation(2, 2));
  return {base_from_camera * marker.translation + cv::Vec3d(camera.x_offset_m, 0, camera.height_m),
          -cv::normalize(into_marker)};
}

ParkingError parkingError(const MarkerObservation& marker, const CameraGeometry& camera) {
  const MarkerInBase placed = markerInBase(marker, camera);
  const cv::Vec3d& position = placed.centre;
  const cv::Vec3d into_marker = -placed.outward_normal;
  const cv::Vec2d normal = -cv::normalize(cv::Vec2d(into_marker[0], into_marker[1]));
  const cv::Vec2d robot(-position[0], -position[1]);  // robot origin relative to the marker
  ParkingError error;
  error.along = robot.dot(normal);
  error.lateral = robot.dot(cv::Vec2d(-normal[1], normal[0]));
  error.phi = std::atan2(error.lateral, error.along);
  error.heading = std::atan2(into_marker[1], into_marker[0]);
  error.bearing = std::atan2(position[1], position[0]);
  return error;
}

struct ParkingServo::Impl {
  vpServo task;
  vpFeaturePoint point;
  vpFeaturePoint point_goal;
  vpFeatureDepth depth;
  vpFeatureDepth depth_goal;
  bool aligning = false;  // the stage to resume after a loss
};

ParkingServo::ParkingServo(const ParkingServoConfig& config)
    : config_(config), impl_(std::make_unique<Impl>()) {
  const std::string error = validate(config);
  if (!error.empty()) throw std::invalid_argument(error);
  search_direction_ = config.search_rate < 0.0 ? -1.0 : 1.0;

  // Camera mounting: eMc has the optical axes (cameraToBase) as rotation columns.
  const cv::Matx33d r = cameraToBase(config.camera.pitch_rad);
  vpRotationMatrix e_R_c;
  for (unsigned i = 0; i < 3; ++i) {
    for (unsigned j = 0; j < 3; ++j) e_R_c[i][j] = r(i, j);
  }
  const vpHomogeneousMatrix e_M_c(
      vpTranslationVector(config.camera.x_offset_m, 0, config.camera.height_m), e_R_c);
  // Unicycle: (v, w) move base_link along its x and about its z.
  vpMatrix e_J_e(6, 2, 0.0);
  e_J_e[0][0] = 1.0;
  e_J_e[5][1] = 1.0;

  vpServo& task = impl_->task;
  task.setServo(vpServo::EYEINHAND_L_cVe_eJe);
  task.setInteractionMatrixType(vpServo::CURRENT, vpServo::PSEUDO_INVERSE);
  task.setLambda(config.gain);
  task.set_cVe(vpVelocityTwistMatrix(e_M_c.inverse()));
  task.set_eJe(e_J_e);
  task.addFeature(impl_->point, impl_->point_goal, vpFeaturePoint::selectX());
  task.addFeature(impl_->depth, impl_->depth_goal);
}

ParkingServo::~ParkingServo() = default;

void ParkingServo::setIntrinsics(const CameraGeometry& camera) {
  config_.camera.fx = camera.fx;
  config_.camera.fy = camera.fy;
  config_.camera.cx = camera.cx;
  config_.camera.cy = camera.cy;
}

bool ParkingServo::withinTolerance(const ParkingError& error, double scale) const {
  return std::abs(error.along - config_.standoff_m) <= scale * config_.position_tolerance &&
         std::abs(error.lateral) <= scale * config_.lateral_tolerance &&
         std::abs(error.heading) <= scale * config_.heading_tolerance_rad;
}

Twist2D ParkingServo::servo(const MarkerObservation& marker, double depth_goal,
                            double bearing_goal) {
  const double z = marker.translation[2];
  const double x = marker.translation[0] / z;
  const double y = marker.translation[1] / z;
  impl_->point.buildFrom(x, y, z);
  impl_->point_goal.buildFrom(-std::tan(bearing_goal), 0.0, depth_goal);
  impl_->depth.buildFrom(x, y, z, std::log(z / depth_goal));
  impl_->depth_goal.buildFrom(0.0, 0.0, depth_goal, 0.0);
  const vpColVector q = impl_->task.computeControlLaw();
  // Far away the depth feature asks for far more speed (~ lambda Z log(Z/Z*)) than allowed.
  // Bound v, then solve the x row of the task for w given that v, so the bearing still
  // converges at lambda (clamping v alone would leave w compensating for motion that does not
  // happen, which pulls the marker to the image centre instead of x*).
  const double linear = clampAbs(q[0], config_.max_linear);
  double angular = q[1];
  const vpMatrix jacobian = impl_->task.getTaskJacobian();
  if (linear != q[0] && std::abs(jacobian[0][1]) > 1e-9) {
    angular =
        (-config_.gain * impl_->task.getError()[0] - jacobian[0][0] * linear) / jacobian[0][1];
  }
  return {linear, clampAbs(angular, config_.max_angular)};
}

// One full turn at search_rate from the search's start; then turns of search_step at
// search_rate, each followed by search_pause still.
Twist2D ParkingServo::search(double time_s) {
  if (!search_started_s_) search_started_s_ = time_s;
  const double rate = std::copysign(config_.search_rate, search_direction_);
  if (config_.search_pause <= 0.0 || rate == 0.0) return {0.0, rate};
  const double stepping_s = time_s - *search_started_s_ - 2.0 * M_PI / std::abs(rate);
  if (stepping_s < 0.0) return {0.0, rate};
  const double turn_s = config_.search_step_rad / std::abs(rate);
  const double phase = std::fmod(stepping_s, turn_s + config_.search_pause);
  return {0.0, phase < turn_s ? rate : 0.0};
}

Twist2D ParkingServo::update(const std::optional<MarkerObservation>& marker, double time_s) {
  if (!marker || !(marker->translation[2] > 0.0)) {
    last_error_.reset();
    if (seen_ && state_ == ParkingState::kParked) return {};
    if (seen_ && time_s - last_seen_s_ <= config_.lost_timeout) {
      state_ = ParkingState::kLost;
      return {};
    }
    // Never seen, or lost too long (it left the view): turn toward where it was last seen.
    state_ = ParkingState::kSearching;
    impl_->aligning = false;
    return search(time_s);
  }
  search_started_s_.reset();
  last_seen_s_ = time_s;
  search_direction_ = marker->translation[0] > 0.0 ? -1.0 : 1.0;  // right of centre: turn right
  seen_ = true;
  const ParkingError error = parkingError(*marker, config_.camera);
  last_error_ = error;

  if (state_ == ParkingState::kParked) {
    if (withinTolerance(error, 2.0)) return {};
    impl_->aligning = false;  // pushed away: approach again
  }
  state_ = impl_->aligning ? ParkingState::kAligning : ParkingState::kApproaching;
  const double max_bearing =
      std::min(config_.max_bearing_rad, bearingInView(*marker, config_.camera));
  const double camera_depth_at_goal = config_.standoff_m - config_.camera.x_offset_m;
  const double depth_error = error.along - config_.standoff_m;

  if (impl_->aligning) {
    if (depth_error >= config_.backoff_m - kArrived) {
      impl_->aligning = false;
      state_ = ParkingState::kApproaching;
    } else {
      // Aim past the back-off point so the stage ends at speed, not in the servo's slow tail.
      return servo(*marker, camera_depth_at_goal + config_.backoff_m + 0.2,
                   clampAbs(config_.steer_gain * error.phi, max_bearing));
    }
  }

  // Lateral already good and nearly there: square the heading up (b* = phi means facing the
  // marker's normal); otherwise keep turning onto the normal while driving.
  const bool square_up =
      std::abs(depth_error) < kArrived && std::abs(error.lateral) <= config_.lateral_tolerance;
  const double bearing_goal =
      square_up ? error.phi : clampAbs(-config_.steer_gain * error.phi, max_bearing);
  const Twist2D command = servo(*marker, camera_depth_at_goal, bearing_goal);
  const bool still = std::abs(command.linear) <= config_.linear_tolerance &&
                     std::abs(command.angular) <= config_.angular_tolerance;
  if (withinTolerance(error, 1.0) && still) {
    state_ = ParkingState::kParked;
    return {};
  }
  if (depth_error < kArrived && std::abs(error.lateral) > config_.lateral_tolerance) {
    impl_->aligning = true;  // arrived off the normal: back off and come in again
    state_ = ParkingState::kAligning;
  }
  return command;
}

}  // namespace follow_bot
