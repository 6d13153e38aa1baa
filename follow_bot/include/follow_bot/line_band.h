// A band of image rows that looks at one stretch of floor: where it lands for a camera's
// mounting, what the line detector measured in it, and the line's centre on the floor from that.
#pragma once

#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot/FollowerDefaults.h"
#include "follow_bot/common.h"
#include "follow_bot_common/ground_projection.h"

namespace follow_bot {

// A horizontal band of image rows centred on the floor `distance_m` ahead of base_link (in the
// image's centre column), `rows` tall. Its height stays in rows, not a depth of floor: the line's
// width in pixels already shrinks with distance, and a fixed row count keeps the pixel count
// (min_pixels) and the centroid's noise about the same wherever the band lands.
struct BandConfig {
  double distance_m = FollowerDefaults::band_distance;
  int rows = FollowerDefaults::band_rows;
};

// The continuous image row (pixel centres at integers) where the floor point `distance_m` ahead
// of base_link on its x axis appears: the inverse of pixelToGround at u = cx. Empty when that
// point is not in front of the camera (on or behind its image plane) or the input is not finite.
std::optional<double> groundToRow(const CameraGeometry& camera, double distance_m);

// Where a band lands in a frame `image_height` rows tall.
struct BandPlacement {
  int row_begin = 0;  // rows [row_begin, row_end)
  int row_end = 0;
  // m ahead of base_link of the floor at the centre of the placed band (NaN when that row sees
  // no floor: a camera that sees none).
  double distance_m = 0.0;
  // The requested distance is outside the floor the camera sees with margin, so the band was
  // moved to the nearest rows that do: the bottom of the image (too near), or
  // kMinDepressionDeg below the horizon (too far).
  bool clamped = false;
};

// Rays less than this far below the horizon are not used: the floor there is too far away and
// too foreshortened for a line to be measured.
constexpr double kMinDepressionDeg = 2.0;

// The band's rows for this camera: centred on groundToRow(band.distance_m), then clamped into
// [first row at least kMinDepressionDeg below the horizon, image bottom]; a camera that sees no
// such floor gets the bottom rows (clamped). A frame shorter than the band gets all its rows.
BandPlacement placeBand(const CameraGeometry& camera, const BandConfig& band, int image_height);

struct BandMeasurement {
  // The band's fitted floor test: line pixels have min(R, G) - B >= this (0 without the test)
  // where the band is lit, and >= block_min_yellowness[x / 128] in the column block of x.
  int min_yellowness = 0;
  std::vector<int> block_min_yellowness;
  // pixel_count >= min_pixels and, where the band holds several blobs, one of those measured
  // alone has min_pixels.
  bool found = false;
  int pixel_count = 0;  // line pixels in the band: the lecture's m00 / 255
  // Centroid in full-image pixel coordinates (pixel index, as cv::moments); valid whenever
  // pixel_count > 0, including below min_pixels.
  double centroid_x = 0.0;
  double centroid_y = 0.0;
  // Horizontal offset of the centroid from width / 2; positive = line right of image centre.
  double error_px = 0.0;
  double error_normalised = 0.0;  // error_px / (width / 2), within [-1, 1]
  // 0..1: (fraction of scanned rows holding line pixels) x (width sanity), where width sanity
  // is 1 while the mean width per occupied row is <= max_width_fraction of the image width and
  // falls linearly to 0 at the full width. A thin line through the band scores 1; a frame
  // entirely of line colour is found but scores 0; a line ending inside the band scores low.
  double confidence = 0.0;
  // The line's centre: the centroid of the line pixels in whole runs only. A row's run of line
  // pixels that reaches the image's left or right edge is cut there, so its middle is not the
  // line's: where a curve enters or leaves the view the centroid lies up to half a line width
  // off the line (on the floor), while a whole run's middle is on it (a row sees the floor at
  // one depth, so along a row the image is an affine map of the floor). The path law places its
  // sightings with floorCentre() (the spans below); the centroid above stays the lecture's.
  int centre_pixel_count = 0;  // line pixels in runs that reach neither side edge
  // centre_pixel_count >= min_pixels, in at least 5 rows (all of a shorter band): over fewer the
  // line crosses the rows too obliquely for floorCentre() to place its centre.
  bool centre_found = false;
  double centre_x = 0.0;  // full-image pixel coordinates, valid when centre_pixel_count > 0
  double centre_y = 0.0;
  // Each scanned row's whole runs, top to bottom (rows without any left out): where the line's
  // edges cross that row. floorCentre() measures the line's centre on the floor from them.
  struct RowSpan {
    double row = 0.0;    // pixel centres at integers, as centre_y
    double left = 0.0;   // the left edge of the row's first whole run (its first pixel - 0.5)
    double right = 0.0;  // the right edge of its last (last pixel + 0.5)
  };
  std::vector<RowSpan> spans;
  int row_begin = 0;  // rows actually scanned: [row_begin, row_end)
  int row_end = 0;
  double distance_m = 0.0;  // and the rest of the band's placeBand() result
  bool clamped = false;
};

// The line's centre on the floor (base_link: x forward, y left, m) from the band's row spans.
// A curve crosses a far band's rows obliquely, over many columns, so the centroid of its patch
// (centre_x) lies inside the curve, by 0.3-0.9 cm on a 1 m curve seen 1.2 m ahead; a span's
// middle is off the line too where its row cuts the line obliquely. Instead the spans' edges are
// projected to the floor, where the line's two edges are parallel curves, and one quadratic
// across the patch's principal axis (a line for two rows, a constant for one) is fitted to both
// at once, the edges at plus and minus half the line's width from it; the centre is that curve
// at the rows' mean along the axis. Frames through a lens are rectified first. Empty without
// spans or when an edge does not project to the floor.
std::optional<cv::Point2d> floorCentre(const BandMeasurement& band, const CameraGeometry& camera);

}  // namespace follow_bot
