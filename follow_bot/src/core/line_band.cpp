#include "follow_bot/line_band.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace follow_bot {

std::optional<double> groundToRow(const CameraGeometry& camera, double distance_m) {
  // The floor point is `ahead` forward of the optical centre and height_m below it. In the
  // optical frame (see pixelToGround) its depth is ahead cos p + h sin p and its downward
  // coordinate h cos p - ahead sin p; the row is cy + fy * down / depth.
  const double ahead = distance_m - camera.x_offset_m;
  const double sin_p = std::sin(camera.pitch_rad);
  const double cos_p = std::cos(camera.pitch_rad);
  const double depth = ahead * cos_p + camera.height_m * sin_p;
  if (!(depth > 0.0)) return std::nullopt;  // also rejects NaN
  const double row = camera.cy + camera.fy * (camera.height_m * cos_p - ahead * sin_p) / depth;
  if (!std::isfinite(row)) return std::nullopt;
  return row;
}

BandPlacement placeBand(const CameraGeometry& camera, const BandConfig& band, int image_height) {
  BandPlacement placement;
  const double half = (band.rows - 1) / 2.0;  // centre row - first row
  // Rows the band may start on: from the first one kMinDepressionDeg below the horizon (an
  // angle above the optical axis when the pitch exceeds it) to the bottom of the image.
  constexpr double kNever = std::numeric_limits<double>::infinity();
  const double margin_below_axis = kMinDepressionDeg * CV_PI / 180.0 - camera.pitch_rad;
  const double highest = margin_below_axis < CV_PI / 2
                             ? std::ceil(camera.cy + camera.fy * std::tan(margin_below_axis))
                             : kNever;
  const double lowest = std::max(0, image_height - band.rows);
  // No row: the point is under or behind the camera, nearer than any floor it sees.
  const std::optional<double> centre = groundToRow(camera, band.distance_m);
  const double wanted = centre ? std::round(*centre - half) : kNever;
  const double begin = std::max(std::min(std::max(wanted, highest), lowest), 0.0);
  placement.clamped = begin != wanted;
  placement.row_begin = static_cast<int>(begin);
  placement.row_end = std::min(placement.row_begin + band.rows, image_height);
  const std::optional<cv::Point2d> floor = pixelToGround(camera, camera.cx, begin + half);
  placement.distance_m = floor ? floor->x : std::nan("");
  return placement;
}

std::optional<cv::Point2d> floorCentre(const BandMeasurement& band, const CameraGeometry& camera) {
  if (band.spans.empty()) return std::nullopt;
  std::vector<cv::Point2d> raw;
  for (const BandMeasurement::RowSpan& span : band.spans) {
    raw.emplace_back(span.left, span.row);
    raw.emplace_back(span.right, span.row);
  }
  const std::vector<cv::Point2d> pixels = rectifyPixels(camera, raw);
  std::vector<cv::Point2d> left_edge, right_edge;
  cv::Point2d mean(0.0, 0.0);
  for (size_t i = 0; i < pixels.size(); i += 2) {
    const std::optional<cv::Point2d> left = pixelToGround(camera, pixels[i].x, pixels[i].y);
    const std::optional<cv::Point2d> right =
        pixelToGround(camera, pixels[i + 1].x, pixels[i + 1].y);
    if (!left || !right) return std::nullopt;
    left_edge.push_back(*left);
    right_edge.push_back(*right);
    mean += 0.5 * (*left + *right);
  }
  mean *= 1.0 / static_cast<double>(left_edge.size());
  // The patch's principal axis: the direction of the span middles about their mean.
  double sxx = 0.0, sxy = 0.0, syy = 0.0;
  for (size_t i = 0; i < left_edge.size(); ++i) {
    const cv::Point2d d = 0.5 * (left_edge[i] + right_edge[i]) - mean;
    sxx += d.x * d.x;
    sxy += d.x * d.y;
    syy += d.y * d.y;
  }
  const double axis_angle = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
  const cv::Point2d along(std::cos(axis_angle), std::sin(axis_angle));
  const cv::Point2d across(-along.y, along.x);
  // One polynomial n(s) across the axis for the line's centre, the edges at n(s) +- half its
  // width (a fourth unknown): fitted to both edges at once, so each edge's points stand on the
  // ones across from them and the centre is never extrapolated (an edge alone may lie wholly to
  // one side of the mean when the line crosses the rows obliquely).
  const int rows_seen = static_cast<int>(left_edge.size());
  const int terms = std::min(3, rows_seen);
  cv::Mat_<double> design(2 * rows_seen, terms + 1);
  cv::Mat_<double> offset(2 * rows_seen, 1);
  for (int i = 0; i < 2 * rows_seen; ++i) {
    const bool left = i < rows_seen;
    const cv::Point2d d = (left ? left_edge[i] : right_edge[i - rows_seen]) - mean;
    const double s = d.dot(along);
    for (int term = 0; term < terms; ++term) design(i, term) = std::pow(s, term);
    design(i, terms) = left ? 1.0 : -1.0;
    offset(i, 0) = d.dot(across);
  }
  cv::Mat_<double> coefficients;
  if (!cv::solve(design, offset, coefficients, cv::DECOMP_QR)) return std::nullopt;
  const cv::Point2d centre = mean + coefficients(0) * across;
  if (!std::isfinite(centre.x) || !std::isfinite(centre.y)) return std::nullopt;
  return centre;
}

}  // namespace follow_bot
