#include "follow_bot/line_path.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

namespace follow_bot {
namespace {

// Below this turn per frame the exact arc loses precision to cancellation; its series is exact
// to double precision there.
constexpr double kSmallTurnRad = 1e-6;

bool isFinite(const cv::Point2d& p) { return std::isfinite(p.x) && std::isfinite(p.y); }

cv::Point2d rotated(const cv::Point2d& d, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return cv::Point2d(c * d.x - s * d.y, s * d.x + c * d.y);
}

// A pose in base_link at the latest frame.
struct Pose2D {
  cv::Point2d position{0.0, 0.0};
  double yaw = 0.0;
};

// `positions` as seen from `pose`.
std::vector<cv::Point2d> seenFrom(const std::vector<cv::Point2d>& positions, const Pose2D& pose) {
  std::vector<cv::Point2d> seen;
  seen.reserve(positions.size());
  for (const cv::Point2d& p : positions) seen.push_back(rotated(p - pose.position, -pose.yaw));
  return seen;
}

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

// The path near the base, in base_link.
struct PathAtBase {
  double lateral = 0.0;
  double heading = 0.0;
  double curvature = 0.0;  // the fitted parabola's, at the foot
  // The parabola's curvature at the middle of the fitted window: the window's curvature where
  // the line is an arc, which a parabola's falls away from off its vertex (at the window's
  // end, where a bridge starts, it reads a 0.6 m arc 3 % too wide).
  double window_curvature = 0.0;
  double before_start = 0.0;  // m the base's foot lies before the first fitted point, if any
};

// Fits the remembered points around the one nearest the base with n = a + b s + c s^2 in a
// frame (s along the path, n to its left) and evaluates it at the foot of the base. Only the
// path's direction uses the points' order (their stamps); duplicates, the look-ahead band's
// points and noise just weigh in the least squares. Empty when the points are too few or too
// short, or the base lies beyond either end of them by more than max_extrapolation.
std::optional<PathAtBase> fitPathAtBase(const std::vector<cv::Point2d>& positions,
                                        const std::vector<double>& stamps, double fit_length,
                                        double max_extrapolation) {
  if (positions.empty()) return std::nullopt;
  const cv::Point2d anchor = *std::min_element(
      positions.begin(), positions.end(),
      [](const cv::Point2d& a, const cv::Point2d& b) { return a.dot(a) < b.dot(b); });

  // Candidates: points within fit_length of the anchor. Their principal axis is the path's
  // direction, oriented the way the points were seen (the robot drives forward along it).
  std::vector<size_t> candidates;
  cv::Point2d mean(0.0, 0.0);
  double mean_stamp = 0.0;
  for (size_t i = 0; i < positions.size(); ++i) {
    const cv::Point2d offset = positions[i] - anchor;
    if (offset.dot(offset) > fit_length * fit_length) continue;
    candidates.push_back(i);
    mean += positions[i];
    mean_stamp += stamps[i];
  }
  constexpr size_t kMinPoints = 3;
  if (candidates.size() < kMinPoints) return std::nullopt;
  mean *= 1.0 / candidates.size();
  mean_stamp /= candidates.size();
  double sxx = 0.0, sxy = 0.0, syy = 0.0;
  for (size_t i : candidates) {
    const cv::Point2d d = positions[i] - mean;
    sxx += d.x * d.x;
    sxy += d.x * d.y;
    syy += d.y * d.y;
  }
  const double axis_angle = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
  cv::Point2d along(std::cos(axis_angle), std::sin(axis_angle));
  double time_trend = 0.0;
  for (size_t i : candidates)
    time_trend += (stamps[i] - mean_stamp) * (positions[i] - mean).dot(along);
  if (time_trend < 0.0 || (time_trend == 0.0 && along.x < 0.0)) along = -along;
  const cv::Point2d left(-along.y, along.x);

  // A window of fit_length around the anchor, slid inwards at the ends of the path so that the
  // start of the path is fitted over as much length as the middle.
  double s_min = 0.0, s_max = 0.0;
  for (size_t i : candidates) {
    const double s = (positions[i] - anchor).dot(along);
    s_min = std::min(s_min, s);
    s_max = std::max(s_max, s);
  }
  const double window_begin =
      std::clamp(-0.5 * fit_length, s_min, std::max(s_min, s_max - fit_length));
  std::vector<cv::Point2d> local;  // (s, n)
  double kept_min = window_begin + fit_length, kept_max = window_begin;
  for (size_t i : candidates) {
    const cv::Point2d d = positions[i] - anchor;
    const double s = d.dot(along);
    if (s < window_begin || s > window_begin + fit_length) continue;
    local.emplace_back(s, d.dot(left));
    kept_min = std::min(kept_min, s);
    kept_max = std::max(kept_max, s);
  }
  // Curvature needs length (its noise grows as span^-2 at a given point count), so shorter
  // stretches fit a line.
  const double span = kept_max - kept_min;
  constexpr double kMinLineSpanFraction = 0.1;
  if (local.size() < kMinPoints || span < kMinLineSpanFraction * fit_length) return std::nullopt;
  const int terms = span >= 0.5 * fit_length ? 3 : 2;
  cv::Mat_<double> design(static_cast<int>(local.size()), terms);
  cv::Mat_<double> lateral(static_cast<int>(local.size()), 1);
  for (int row = 0; row < design.rows; ++row) {
    const double s = local[row].x;
    design(row, 0) = 1.0;
    design(row, 1) = s;
    if (terms == 3) design(row, 2) = s * s;
    lateral(row, 0) = local[row].y;
  }
  cv::Mat_<double> coefficients;
  if (!cv::solve(design, lateral, coefficients, cv::DECOMP_QR)) return std::nullopt;
  const double a = coefficients(0), b = coefficients(1), c = terms == 3 ? coefficients(2) : 0.0;

  // Foot of the base on the curve: Newton on the derivative of the squared distance, from the
  // base's own along-path coordinate (the curve is nearly straight over the window).
  const double base_s = -anchor.dot(along);
  const double base_n = -anchor.dot(left);
  double s = base_s;
  for (int iteration = 0; iteration < 4; ++iteration) {
    const double n = a + s * (b + s * c);
    const double slope = b + 2.0 * c * s;
    const double gradient = (s - base_s) + (n - base_n) * slope;
    const double hessian = 1.0 + slope * slope + (n - base_n) * 2.0 * c;
    if (!(hessian > 0.0)) break;
    s -= gradient / hessian;
  }
  if (!(s >= kept_min - max_extrapolation && s <= kept_max + max_extrapolation)) {
    return std::nullopt;
  }
  const double slope = b + 2.0 * c * s;
  const cv::Point2d foot = anchor + s * along + (a + s * (b + s * c)) * left;
  cv::Point2d tangent = along + slope * left;
  tangent *= 1.0 / std::sqrt(tangent.dot(tangent));
  PathAtBase path;
  path.before_start = std::max(0.0, kept_min - s);
  path.lateral = foot.dot(cv::Point2d(-tangent.y, tangent.x));
  path.heading = std::atan2(tangent.y, tangent.x);
  const auto curvatureAt = [&](double at) {
    const double slope_at = b + 2.0 * c * at;
    return 2.0 * c / std::pow(1.0 + slope_at * slope_at, 1.5);
  };
  path.curvature = curvatureAt(s);
  path.window_curvature = curvatureAt(0.5 * (kept_min + kept_max));
  if (!std::isfinite(path.lateral) || !std::isfinite(path.heading) ||
      !std::isfinite(path.curvature) || !std::isfinite(path.window_curvature)) {
    return std::nullopt;
  }
  return path;
}

// Pure pursuit: the curvature of the arc tangent to the robot's heading through the point
// ahead whose distance is the first at or beyond `lookahead` (else the furthest). Empty when
// no point lies ahead.
std::optional<double> pursuitCurvature(const std::vector<cv::Point2d>& positions,
                                       double lookahead) {
  std::optional<cv::Point2d> target;
  double target_distance = 0.0;
  for (const cv::Point2d& p : positions) {
    if (!(p.x > 0.0)) continue;
    const double distance = std::sqrt(p.dot(p));
    const bool beyond = distance >= lookahead;
    const bool target_beyond = target && target_distance >= lookahead;
    const bool better = !target || (beyond && (!target_beyond || distance < target_distance)) ||
                        (!beyond && !target_beyond && distance > target_distance);
    if (better) {
      target = p;
      target_distance = distance;
    }
  }
  if (!target) return std::nullopt;
  const double curvature = 2.0 * target->y / (target_distance * target_distance);
  if (!std::isfinite(curvature)) return std::nullopt;
  return curvature;
}

// The path's direction at `at` and the curvature of the window fitted to the points around it.
struct PathDirection {
  cv::Point2d tangent;  // unit
  double curvature = 0.0;
};
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

// Spacing of the samples along a bridge: about the sightings' own at the default speed, so the
// fit weighs a bridged stretch like a seen one.
constexpr double kBridgeSampleSpacing = 0.01;

// The end of the arc of curvature `curvature` that leaves `from` along unit `tangent` and runs
// for `length`, and its tangent there.
std::pair<cv::Point2d, cv::Point2d> alongArc(const cv::Point2d& from, const cv::Point2d& tangent,
                                             double curvature, double length) {
  const double turn = curvature * length;
  const cv::Point2d left(-tangent.y, tangent.x);
  // sin(turn) / curvature and (1 - cos(turn)) / curvature, by their series near a straight.
  const bool straight = std::abs(turn) < kSmallTurnRad;
  const double ahead = straight ? length : std::sin(turn) / curvature;
  const double aside = straight ? 0.5 * length * turn : (1.0 - std::cos(turn)) / curvature;
  return {from + ahead * tangent + aside * left, std::cos(turn) * tangent + std::sin(turn) * left};
}

// Appends points about kBridgeSampleSpacing apart along the arc (curvature, length) from
// `from`, excluding `from` itself, with stamps interpolated from `from_stamp` at a rate per
// metre of `stamp_rate`.
void sampleArc(const cv::Point2d& from, const cv::Point2d& tangent, double curvature, double length,
               double from_stamp, double stamp_rate, std::vector<cv::Point2d>& positions,
               std::vector<double>& stamps) {
  const int samples = static_cast<int>(std::ceil(length / kBridgeSampleSpacing));
  for (int i = 1; i <= samples; ++i) {
    const double run = length * i / samples;
    positions.push_back(alongArc(from, tangent, curvature, run).first);
    stamps.push_back(from_stamp + stamp_rate * run);
  }
}

// The bridge from `from` (tangent and curvature `start`) to `to`: the remembered stretch's own
// arc continued, then the arc that reaches `to` along `end_tangent`, the first arc as short as
// that allows (a curve that ends where the camera lost it, then the next segment: exact for a
// curve running into a straight or into another curve). Without `end_tangent`, or when no
// such pair of arcs exists, the single arc from `from` through `to`. Appends the samples
// (without `from`; with `to`) and stamps interpolated between the ends'.
void sampleBridge(const cv::Point2d& from, const PathDirection& start, double from_stamp,
                  const cv::Point2d& to, const std::optional<cv::Point2d>& end_tangent,
                  double to_stamp, std::vector<cv::Point2d>& positions,
                  std::vector<double>& stamps) {
  // The arc from `at` along `tangent` through `to`: its curvature, length and end tangent.
  struct Arc {
    double curvature = 0.0;
    double length = 0.0;
    cv::Point2d end_tangent;
  };
  const auto arcTo = [&](const cv::Point2d& at, const cv::Point2d& tangent) -> std::optional<Arc> {
    const cv::Point2d chord = to - at;
    const double distance = std::sqrt(chord.dot(chord));
    if (!(distance > 0.0) || chord.dot(tangent) <= 0.0) return std::nullopt;
    const cv::Point2d unit = chord * (1.0 / distance);
    const double sine = tangent.x * unit.y - tangent.y * unit.x;  // of the angle to the chord
    const double half_turn = std::asin(std::clamp(sine, -1.0, 1.0));
    const double length =
        std::abs(half_turn) < kSmallTurnRad ? distance : distance * half_turn / sine;
    return Arc{2.0 * sine / distance, length, 2.0 * tangent.dot(unit) * unit - tangent};
  };
  const auto mismatch = [&](const Arc& arc) {  // rad, from the arc's end tangent to end_tangent
    const cv::Point2d& t = arc.end_tangent;
    return std::atan2(t.x * end_tangent->y - t.y * end_tangent->x, t.dot(*end_tangent));
  };
  const cv::Point2d chord = to - from;
  const double distance = std::sqrt(chord.dot(chord));

  // The first arc's length: the smallest root of the end tangents' mismatch, bracketed on a
  // grid over the chord's length and refined by bisection.
  double first_length = 0.0;
  if (end_tangent) {
    constexpr int kGrid = 64;
    constexpr int kBisections = 30;
    const auto mismatchAfter = [&](double length) -> std::optional<double> {
      const auto [at, tangent] = alongArc(from, start.tangent, start.curvature, length);
      const std::optional<Arc> arc = arcTo(at, tangent);
      if (!arc) return std::nullopt;
      return mismatch(*arc);
    };
    std::optional<double> previous = mismatchAfter(0.0);
    for (int i = 1; i <= kGrid && previous; ++i) {
      double high = distance * i / kGrid;
      const std::optional<double> current = mismatchAfter(high);
      if (!current) break;
      // A sign change through zero, not across +-pi.
      if (*previous * *current <= 0.0 && std::abs(*previous - *current) < CV_PI) {
        double low = distance * (i - 1) / kGrid;
        double low_value = *previous;
        for (int b = 0; b < kBisections; ++b) {
          const double middle = 0.5 * (low + high);
          const std::optional<double> value = mismatchAfter(middle);
          if (!value) break;
          if (low_value * *value <= 0.0) {
            high = middle;
          } else {
            low = middle;
            low_value = *value;
          }
        }
        first_length = high;
        break;
      }
      previous = current;
    }
  }
  const auto [joint, joint_tangent] = alongArc(from, start.tangent, start.curvature, first_length);
  const std::optional<Arc> second = arcTo(joint, joint_tangent);
  if (!second) return;
  const double stamp_rate = (to_stamp - from_stamp) / (first_length + second->length);
  sampleArc(from, start.tangent, start.curvature, first_length, from_stamp, stamp_rate, positions,
            stamps);
  sampleArc(joint, joint_tangent, second->curvature, second->length,
            from_stamp + stamp_rate * first_length, stamp_rate, positions, stamps);
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

cv::Point2d arcDisplacement(double distance, double turn) {
  if (std::abs(turn) < kSmallTurnRad) {
    return cv::Point2d(distance * (1.0 - turn * turn / 6.0), distance * turn / 2.0);
  }
  return cv::Point2d(distance * std::sin(turn) / turn, distance * (1.0 - std::cos(turn)) / turn);
}

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
