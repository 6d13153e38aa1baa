#include "follow_bot/line_path.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

namespace follow_bot {
namespace {

// The direction the band's line runs on the floor, followed away from the robot: from the
// middle of its nearest whole run to that of its furthest. Empty when the band has fewer than
// two rows of whole runs or they meet on the floor.
std::optional<cv::Point2d> floorDirection(const BandMeasurement& band,
                                          const CameraGeometry& camera) {
  if (band.spans.size() < 2) return std::nullopt;
  const auto middle = [&](const BandMeasurement::RowSpan& span) {
    const cv::Point2d pixel =
        rectifyPixel(camera, cv::Point2d(0.5 * (span.left + span.right), span.row));
    return pixelToGround(camera, pixel.x, pixel.y);
  };
  const std::optional<cv::Point2d> far = middle(band.spans.front());  // spans run top to bottom
  const std::optional<cv::Point2d> near = middle(band.spans.back());
  if (!far || !near) return std::nullopt;
  const cv::Point2d along = *far - *near;
  const double length = std::sqrt(along.dot(along));
  if (!(length > 1e-6)) return std::nullopt;
  return along * (1.0 / length);
}

// The path's direction at `at` and the curvature of the window fitted to the points around it.
std::optional<PathDirection> directionAt(const cv::Point2d& at,
                                         const std::vector<cv::Point2d>& positions,
                                         const std::vector<double>& stamps,
                                         const PathConfig& config) {
  std::vector<cv::Point2d> shifted;
  shifted.reserve(positions.size());
  for (const cv::Point2d& p : positions) shifted.push_back(p - at);
  const std::optional<PathAtBase> path =
      fitPathAtBase(shifted, stamps, config.fit_length, config.max_extrapolation);
  if (!path) return std::nullopt;
  return PathDirection{{std::cos(path->heading), std::sin(path->heading)}, path->window_curvature};
}

const SteeringConfig& validated(const SteeringConfig& config, const CameraGeometry& camera) {
  std::string error = validate(config);
  if (error.empty()) error = validate(camera);
  if (!error.empty()) throw std::invalid_argument("PathLaw: " + error);
  return config;
}

}  // namespace

PathLaw::PathLaw(const SteeringConfig& config, const CameraGeometry& camera)
    : config_(validated(config, camera)), camera_(camera), fallback_(config) {}

void PathLaw::reset() {
  fallback_.reset();
  points_.clear();
  bridges_.clear();
  stretch_end_.reset();
  path_state_ = PathState();
  following_ = false;
  has_stamp_ = false;
  last_sighting_ = LineMeasurement();
  sent_.clear();
  travel_direction_.reset();
}

LineState PathLaw::state() const { return following_ ? LineState::kFollowing : fallback_.state(); }

std::vector<cv::Point2d> PathLaw::pathPoints() const {
  std::vector<cv::Point2d> positions;
  positions.reserve(points_.size());
  for (const PathPoint& point : points_) positions.push_back(point.position);
  return positions;
}

Twist2D PathLaw::step(const LineObservation& frame) {
  const LineMeasurement& measurement = frame.measurement;
  const double stamp = frame.stamp;
  if (!std::isfinite(stamp)) return Twist2D();
  if (has_stamp_ && stamp < last_stamp_) reset();
  const double dt = has_stamp_ ? stamp - last_stamp_ : 0.0;
  has_stamp_ = true;
  last_stamp_ = stamp;

  const double latency = frame.latency.value_or(config_.path.command_latency);
  moveMemory(frame.applied, dt);
  recordSent(frame.sent, dt, stamp, latency);
  forgetStalePoints(stamp);
  const LineMeasurement taken = remember(measurement, stamp);

  std::vector<cv::Point2d> positions;
  std::vector<double> stamps;
  for (const PathPoint& point : points_) {
    positions.push_back(point.position);
    stamps.push_back(point.stamp);
  }
  appendBridges(positions, stamps);

  // Where the commands still to be executed take the base: the commands sent over the last
  // latency, replayed from here.
  Pose2D predicted;
  const double latency_start = stamp - latency;
  for (const SentCommand& command : sent_) {
    const double held = command.end - std::max(command.begin, latency_start);
    if (!(held > 0.0)) continue;
    predicted.position += rotated(
        arcDisplacement(command.twist.linear * held, command.twist.angular * held), predicted.yaw);
    predicted.yaw += command.twist.angular * held;
  }
  if (!isFinite(predicted.position) || !std::isfinite(predicted.yaw)) predicted = Pose2D();
  positions = seenFrom(positions, predicted);

  path_state_ = PathState();
  const std::optional<double> pursuit = pursuitCurvature(positions, config_.path.start_lookahead);
  std::optional<double> curvature = pursuit;
  if (const std::optional<PathAtBase> path = fitPathAtBase(
          positions, stamps, config_.path.fit_length, config_.path.max_extrapolation)) {
    travel_direction_ =
        rotated(cv::Point2d(std::cos(path->heading), std::sin(path->heading)), predicted.yaw);
    travel_stamp_ = stamp;
    path_state_.valid = true;
    path_state_.lateral = path->lateral;
    path_state_.heading = path->heading;
    path_state_.curvature = path->curvature;
    curvature = path->curvature + config_.path.heading_gain * std::sin(path->heading) +
                config_.path.lateral_gain * path->lateral;
    // Extended backwards past the points the fit is a guess (a quadratic fitted across the
    // start of a curve tilts its extension), so pure pursuit hands over to it gradually as the
    // path reaches the base. before_start > 0 implies max_extrapolation > 0.
    if (pursuit && path->before_start > 0.0) {
      const double pursuit_weight = path->before_start / config_.path.max_extrapolation;
      curvature = (1.0 - pursuit_weight) * *curvature + pursuit_weight * *pursuit;
    }
  }

  following_ = curvature.has_value();
  if (!following_) {
    // Nothing left ahead: the fallback's lost-line search takes over, and whatever is seen
    // next starts a fresh path.
    points_.clear();
    bridges_.clear();
    stretch_end_.reset();
    path_state_.points = 0;
    return fallback_.step(LineObservation{taken, stamp, frame.applied, frame.sent, frame.latency});
  }
  path_state_.points = static_cast<int>(points_.size());
  // Keeps the fallback's clock and last side in step, so it starts from the end of the path.
  fallback_.step(LineObservation{last_sighting_, stamp, frame.applied, frame.sent, frame.latency});
  return drive(*curvature);
}

void PathLaw::moveMemory(const Twist2D& applied, double dt) {
  if ((points_.empty() && !travel_direction_) || dt <= 0.0) return;
  const double distance = applied.linear * dt;
  const double turn = applied.angular * dt;
  if (dt > config_.path.max_frame_gap || !std::isfinite(distance) || !std::isfinite(turn)) {
    points_.clear();
    bridges_.clear();
    stretch_end_.reset();
    travel_direction_.reset();
    return;
  }
  // Points stay put in the world, so in the new frame they move by the inverse motion.
  const cv::Point2d displacement = arcDisplacement(distance, turn);
  for (PathPoint& point : points_) point.position = rotated(point.position - displacement, -turn);
  for (BridgeStart& bridge : bridges_) {
    bridge.position = rotated(bridge.position - displacement, -turn);
    bridge.tangent = rotated(bridge.tangent, -turn);
  }
  if (stretch_end_) {
    stretch_end_->position = rotated(stretch_end_->position - displacement, -turn);
    stretch_end_->tangent = rotated(stretch_end_->tangent, -turn);
  }
  if (travel_direction_) travel_direction_ = rotated(*travel_direction_, -turn);
}

void PathLaw::recordSent(const Twist2D& sent, double dt, double stamp, double latency) {
  if (dt > 0.0) sent_.push_back(SentCommand{stamp - dt, stamp, sent});
  while (!sent_.empty() && sent_.front().end <= stamp - latency) {
    sent_.pop_front();
  }
}

bool PathLaw::keepsDirection(const BandMeasurement& band, double stamp) const {
  if (!points_.empty() || !travel_direction_ ||
      stamp - travel_stamp_ > config_.path.max_point_age) {
    return true;
  }
  const std::optional<cv::Point2d> direction = floorDirection(band, camera_);
  return direction && direction->dot(*travel_direction_) > 0.0;
}

void PathLaw::forgetStalePoints(double stamp) {
  const auto stale = [&](const PathPoint& point) {
    return !isFinite(point.position) || point.position.x < -config_.path.keep_behind ||
           stamp - point.stamp > config_.path.max_point_age;
  };
  points_.erase(std::remove_if(points_.begin(), points_.end(), stale), points_.end());
}

LineMeasurement PathLaw::remember(const LineMeasurement& measurement, double stamp) {
  if (!measurement.ok()) return measurement;
  const auto seen = [&](const BandMeasurement& band) {
    return band.found && band.confidence >= config_.min_confidence;
  };
  LineMeasurement taken = measurement;
  if (seen(taken.band) && !keepsDirection(taken.band, stamp)) taken.band.found = false;
  if (seen(taken.look_ahead) && !keepsDirection(taken.look_ahead, stamp)) {
    taken.look_ahead.found = false;
  }
  const bool near = seen(taken.band);
  const bool ahead = seen(taken.look_ahead);
  // Only a band holding whole runs of the line knows where its centre is (centre_found); a line cut
  // by the image's side edge is remembered from the frames that see it whole, and is still a
  // sighting for the fallback.
  if (near && measurement.band.centre_found) rememberBand(measurement.band, false, stamp);
  if (ahead && measurement.look_ahead.centre_found)
    rememberBand(measurement.look_ahead, true, stamp);
  while (points_.size() > static_cast<size_t>(config_.path.max_points)) points_.pop_front();
  if (!near && !ahead) return taken;
  last_sighting_ = taken;
  // The fallback steers on the near band only; a look-ahead sighting alone stands in for it so
  // the fallback still learns which side the line was on.
  if (!near) last_sighting_.band = taken.look_ahead;
  return taken;
}

void PathLaw::rememberBand(const BandMeasurement& band, bool look_ahead, double stamp) {
  const std::optional<cv::Point2d> ground = floorCentre(band, camera_);
  if (!ground) return;
  const auto latest_of_band =
      std::find_if(points_.rbegin(), points_.rend(),
                   [&](const PathPoint& point) { return point.look_ahead == look_ahead; });
  if (latest_of_band != points_.rend()) {
    const cv::Point2d step = *ground - latest_of_band->position;
    const double spacing = config_.path.min_point_spacing;
    if (step.dot(step) < spacing * spacing) return;
    const double gap = config_.path.bridge_gap;
    if (!look_ahead && step.dot(step) >= gap * gap) startBridge(*latest_of_band, *ground, stamp);
  }
  points_.push_back(PathPoint{*ground, stamp, look_ahead});
  if (!look_ahead) stretch_end_ = stretchEnd(points_.back());
}

std::optional<PathLaw::BridgeStart> PathLaw::stretchEnd(const PathPoint& end) {
  std::vector<cv::Point2d> positions;
  std::vector<double> stamps;
  for (const PathPoint& point : points_) {
    if (point.look_ahead || point.stamp > end.stamp) continue;
    positions.push_back(point.position);
    stamps.push_back(point.stamp);
  }
  appendBridges(positions, stamps);  // the stretch may be short and end an earlier jump
  const std::optional<PathDirection> direction =
      directionAt(end.position, positions, stamps, config_.path);
  if (!direction) return std::nullopt;
  return BridgeStart{end.position, direction->tangent, direction->curvature, end.stamp, 0.0};
}

void PathLaw::startBridge(const PathPoint& before, const cv::Point2d& after, double stamp) {
  // Fitted when `before`, the band's latest sighting, was seen (empty: too few points then, and
  // fewer now).
  std::optional<BridgeStart> start = stretch_end_;
  // A jump backwards or sideways is not the line continuing.
  if (!start || (after - before.position).dot(start->tangent) <= 0.0) return;
  start->position = before.position;
  start->end_stamp = stamp;
  bridges_.push_back(*start);
}

void PathLaw::appendBridges(std::vector<cv::Point2d>& positions, std::vector<double>& stamps) {
  const size_t first_sample = positions.size();
  for (auto bridge = bridges_.begin(); bridge != bridges_.end();) {
    // The band's sightings past the jump up to the next one, oldest first.
    const auto next = std::next(bridge);
    std::vector<cv::Point2d> past;
    std::vector<double> past_stamps;
    for (const PathPoint& point : points_) {
      if (point.look_ahead || point.stamp < bridge->end_stamp) continue;
      if (next != bridges_.end() && point.stamp > next->stamp) break;
      past.push_back(point.position);
      past_stamps.push_back(point.stamp);
    }
    if (past.empty()) {  // forgotten: the bridge lies behind the base
      bridge = bridges_.erase(bridge);
      continue;
    }
    const PathDirection start{bridge->tangent, bridge->curvature};
    // Too few sightings past the jump for a direction yet: the single arc through the first.
    std::optional<cv::Point2d> end_tangent;
    if (const std::optional<PathDirection> end =
            directionAt(past.front(), past, past_stamps, config_.path)) {
      end_tangent = end->tangent;
    }
    sampleBridge(bridge->position, start, bridge->stamp, past.front(), end_tangent,
                 past_stamps.front(), positions, stamps);
    ++bridge;
  }
  // Samples behind the base are forgotten as sightings would be.
  for (size_t i = positions.size(); i-- > first_sample;) {
    if (positions[i].x < -config_.path.keep_behind || !isFinite(positions[i])) {
      positions.erase(positions.begin() + i);
      stamps.erase(stamps.begin() + i);
    }
  }
}

Twist2D PathLaw::drive(double curvature) const {
  double linear = config_.max_linear;
  if (std::abs(curvature) * linear > config_.max_angular) {
    linear = std::max(config_.min_linear, config_.max_angular / std::abs(curvature));
  }
  return Twist2D{linear, std::clamp(linear * curvature, -config_.max_angular, config_.max_angular)};
}

}  // namespace follow_bot
