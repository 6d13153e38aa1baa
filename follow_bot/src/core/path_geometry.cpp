#include "follow_bot/path_geometry.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>
#include <vector>

namespace follow_bot {

namespace {

// Below this turn per frame the exact arc loses precision to cancellation; its series is exact
// to double precision there.
constexpr double kSmallTurnRad = 1e-6;

// Spacing of the samples along a bridge: about the sightings' own at the default speed, so the
// fit weighs a bridged stretch like a seen one.
constexpr double kBridgeSampleSpacing = 0.01;

}  // namespace

bool isFinite(const cv::Point2d& p) { return std::isfinite(p.x) && std::isfinite(p.y); }

cv::Point2d rotated(const cv::Point2d& d, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return cv::Point2d(c * d.x - s * d.y, s * d.x + c * d.y);
}

std::vector<cv::Point2d> seenFrom(const std::vector<cv::Point2d>& positions, const Pose2D& pose) {
  std::vector<cv::Point2d> seen;
  seen.reserve(positions.size());
  for (const cv::Point2d& p : positions) seen.push_back(rotated(p - pose.position, -pose.yaw));
  return seen;
}

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

cv::Point2d arcDisplacement(double distance, double turn) {
  if (std::abs(turn) < kSmallTurnRad) {
    return cv::Point2d(distance * (1.0 - turn * turn / 6.0), distance * turn / 2.0);
  }
  return cv::Point2d(distance * std::sin(turn) / turn, distance * (1.0 - std::cos(turn)) / turn);
}

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

}  // namespace follow_bot
