// Path geometry on the floor, in base_link (x forward, y left, metres): what PathLaw builds its
// remembered path from. Moving points with the robot, fitting the path near the base, pure
// pursuit, and the arcs that bridge a stretch the camera did not see.
#pragma once

#include <optional>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

namespace follow_bot {

bool isFinite(const cv::Point2d& p);
// `d` turned by `angle` rad, counter-clockwise (towards y).
cv::Point2d rotated(const cv::Point2d& d, double angle);

// A pose in base_link at the latest frame.
struct Pose2D {
  cv::Point2d position{0.0, 0.0};
  double yaw = 0.0;
};

// `positions` as seen from `pose`.
std::vector<cv::Point2d> seenFrom(const std::vector<cv::Point2d>& positions, const Pose2D& pose);

// The displacement over the exact arc of `distance` m turning `turn` rad, in the frame at its
// start (x forward, y left).
cv::Point2d arcDisplacement(double distance, double turn);

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
                                        double max_extrapolation);

// Pure pursuit: the curvature of the arc tangent to the robot's heading through the point
// ahead whose distance is the first at or beyond `lookahead` (else the furthest). Empty when
// no point lies ahead.
std::optional<double> pursuitCurvature(const std::vector<cv::Point2d>& positions, double lookahead);

// The path's direction at a point and the curvature of the window fitted to the points around
// it.
struct PathDirection {
  cv::Point2d tangent;  // unit
  double curvature = 0.0;
};

// The end of the arc of curvature `curvature` that leaves `from` along unit `tangent` and runs
// for `length`, and its tangent there.
std::pair<cv::Point2d, cv::Point2d> alongArc(const cv::Point2d& from, const cv::Point2d& tangent,
                                             double curvature, double length);

// Appends points about 1 cm apart (about the sightings' own at the default speed, so the fit
// weighs a bridged stretch like a seen one) along the arc (curvature, length) from `from`,
// excluding `from` itself, with stamps interpolated from `from_stamp` at a rate per metre of
// `stamp_rate`.
void sampleArc(const cv::Point2d& from, const cv::Point2d& tangent, double curvature, double length,
               double from_stamp, double stamp_rate, std::vector<cv::Point2d>& positions,
               std::vector<double>& stamps);

// The bridge from `from` (tangent and curvature `start`) to `to`: the remembered stretch's own
// arc continued, then the arc that reaches `to` along `end_tangent`, the first arc as short as
// that allows (a curve that ends where the camera lost it, then the next segment: exact for a
// curve running into a straight or into another curve). Without `end_tangent`, or when no
// such pair of arcs exists, the single arc from `from` through `to`. Appends the samples
// (without `from`; with `to`) and stamps interpolated between the ends'.
void sampleBridge(const cv::Point2d& from, const PathDirection& start, double from_stamp,
                  const cv::Point2d& to, const std::optional<cv::Point2d>& end_tangent,
                  double to_stamp, std::vector<cv::Point2d>& positions,
                  std::vector<double>& stamps);

}  // namespace follow_bot
