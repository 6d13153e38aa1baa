// Finds a coloured floor line in one horizontal band of a BGR camera frame.
//
// The lecture does: cvtColor(BGR->HSV) on the whole frame, inRange, zero every row outside
// [3h/4, 3h/4 + 20), cv::moments. This detector returns the same centroid but only reads the
// band's pixels, and classifies each one in a single pass with the exact result of
// cvtColor + inRange (see HsvBox), accumulating the moments on the fly. The band is placed by
// ground distance for the camera's mounting (placeBand), so it looks at the same stretch of
// floor on any robot; on the default mounting it is the lecture's [3h/4, 3h/4 + 20).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot/FollowerDefaults.h"
#include "follow_bot/common.h"
#include "follow_bot/hsv_box.h"
#include "follow_bot/line_band.h"
#include "follow_bot_common/config_fields.h"
#include "follow_bot_common/ground_projection.h"

namespace follow_bot {

// Defaults: cfg/Follower.cfg's (FollowerDefaults, generated).
struct LineDetectorConfig {
  using Defaults = FollowerDefaults;
  // The lecture's yellow, but V >= 40 where the lecture has 100 (paint in a deep shadow reads
  // V ~70; dark floor is kept out by the floor test below, not by a V floor), and H <= 40 where
  // the lecture has 30 (real paint reads 29-31 in daylight; a sky-lit shadow's bluish tint
  // moves it towards green: 32-34 under a mild tint, 37-38 under a strong one).
  HsvColor lower{Defaults::h_min, Defaults::s_min, Defaults::v_min};
  HsvColor upper{Defaults::h_max, Defaults::s_max, Defaults::v_max};
  BandConfig band;  // on the default mounting, the lecture's band
  // A second band further ahead (higher in the image) for anticipating curves.
  bool look_ahead_enabled = Defaults::look_ahead;
  BandConfig look_ahead{Defaults::look_ahead_distance, Defaults::band_rows};
  // A band is `found` with at least this many line pixels. Measurements with fewer (but > 0)
  // pixels still carry a centroid, which is what the lecture uses.
  int min_pixels = Defaults::min_pixels;
  // The floor test: a line pixel must also be yellower (min(R, G) - B) than the band's floor by
  // floor_margin levels, or by floor_mads median absolute deviations where that is more; the
  // floor's median and MAD are sampled from the band itself every frame (every 4th pixel of
  // every 4th row), so a cast, glare or shadow that moves the whole floor moves the threshold
  // with it, while paint stays far yellower than the floor around it. floor_margin holds where
  // the band's brightest samples (its 99th percentile of max(B, G, R)) reach 120; in a dimmer
  // band every yellowness is dimmer, and the margin dims in proportion, down to a quarter of
  // it: paint in a whole-frame shadow at 30 % of the light is still found. Not where a block is
  // lit beside a shadow: there the band is not dim, it is partly shaded. A shadow over part of the
  // band dims the paint in it and the floor alike: each 128-column block's threshold is scaled by
  // its light (its floor's lower-quartile brightness, max(B, G, R), over the band's), down to half,
  // never up. Where a block is lit (1.5 times the band's light) while most of the band is in
  // shadow, the lit floor beside the shadow's edge is kept out by that block's own threshold,
  // scaled to each pixel's brightness. 0: no floor test, the colour box alone.
  int floor_margin = Defaults::floor_margin;
  double floor_mads = Defaults::floor_mads;
  // The width gate: a blob whose mean width across its direction on the floor (its extent in
  // each row, taken to the floor through the camera model at the band's centre row) exceeds
  // line_width_factor times line_width_m is not the line (a yellow box, a patch of cast floor).
  // Where the image's side edge cuts a blob, what is seen of it counts. Blobs in fewer than 5
  // rows have no measurable direction and pass. 0: no width gate. No gate for blobs far
  // narrower than the line: on real frames worn or blurred paint falls apart into such blobs.
  double line_width_m = Defaults::line_width;
  double line_width_factor = Defaults::line_width_factor;
  // Without a previous sighting, a band whose line pixels form several blobs leaves out the
  // blobs whose mean saturation (HSV's S: (max - min channel) / max) is below this fraction of
  // the most saturated blob's of at least min_pixels: on real floors a colour cast or glare lets
  // patches of floor, or a tinted white line, into the colour box, but they are far less
  // saturated than paint. Saturation, not chroma, because it does not change with the light:
  // paint in a shadow is less chromatic than lit wood floor beside it, but far more saturated.
  // 0: every line pixel counts, as the lecture.
  double blob_saturation_fraction = Defaults::blob_saturation_fraction;
  // Confidence falls once the line's mean width per row exceeds this fraction of the image
  // width (a frame full of yellow is not a line); see BandMeasurement::confidence.
  double max_width_fraction = 0.35;

  static constexpr auto fields() {
    using C = LineDetectorConfig;
    return std::make_tuple(
        cfgField("look_ahead_enabled", &C::look_ahead_enabled, {}, "look_ahead"),
        cfgField("min_pixels", &C::min_pixels, atLeast(1)),
        field("max_width_fraction", &C::max_width_fraction, aboveAtMost(0.0, 1.0)),
        cfgField("blob_saturation_fraction", &C::blob_saturation_fraction, inRange(0.0, 1.0)),
        cfgField("floor_margin", &C::floor_margin, inRange(0, 255)),
        cfgField("floor_mads", &C::floor_mads, atLeast(0.0)),
        cfgField("line_width_m", &C::line_width_m, positive(), "line_width"),
        cfgField("line_width_factor", &C::line_width_factor, atLeast(0.0)));
  }
};

// Empty when the configuration is usable, otherwise a message naming the first bad field.
std::string validate(const LineDetectorConfig& config);

struct LineMeasurement {
  std::string error;  // why the frame was rejected; empty when it was processed
  int image_width = 0;
  int image_height = 0;
  BandMeasurement band;
  BandMeasurement look_ahead;  // left empty unless look-ahead is enabled
  bool ok() const { return error.empty(); }
};

class LineDetector {
 public:
  // `camera`: intrinsics and mounting, which place the bands (placeBand). Throws
  // std::invalid_argument with the validate() message when the configuration or the camera is
  // unusable (and std::runtime_error in the HsvBox case above). Builds the HsvBox tables: ~2 ms.
  explicit LineDetector(const LineDetectorConfig& config = LineDetectorConfig(),
                        const CameraGeometry& camera = CameraGeometry());

  // Measures the line in a CV_8UC3 BGR frame. Never throws: an empty or non-CV_8UC3 frame gives
  // a measurement with `error` set and nothing found. A frame shorter than the band is scanned
  // over the rows it has.
  LineMeasurement detect(const cv::Mat& bgr) const;

  // As detect(bgr), but keeps each band on the line `previous` (the last measurement) saw there:
  // when that band was found and its mask now holds several 8-connected blobs, only the blob
  // nearest the previous centroid column (of those the width gate keeps) is measured, so a
  // line-coloured patch beside the line (tape, a reflection) does not pull the centroid. With one
  // blob, or no previous sighting, the result is detect(bgr)'s, bit for bit (which leaves out
  // weakly saturated blobs: LineDetectorConfig::blob_saturation_fraction).
  LineMeasurement detect(const cv::Mat& bgr, const LineMeasurement& previous) const;

  // The lecture's mask: CV_8UC1 of the frame's size, 255 on line pixels inside the band(s) (the
  // colour box and the floor test; before the blob rules), 0 elsewhere. Empty for frames detect()
  // rejects.
  cv::Mat debugMask(const cv::Mat& bgr) const;

  // Draws onto the frame the line pixels (magenta), the band outlines (green; look-ahead cyan)
  // and, as in the lecture, a filled red circle of radius 20 at the band centroid (look-ahead:
  // a red ring). Call it on the frame `measurement` came from, before anything else is drawn.
  // Returns false, drawing nothing, when the frame is not CV_8UC3 or not the measured size.
  bool drawDebug(cv::Mat& bgr, const LineMeasurement& measurement) const;

  const LineDetectorConfig& config() const { return config_; }
  const CameraGeometry& camera() const { return camera_; }

 private:
  // One row's line pixels, fed in increasing column order, and the runs of them that reach the
  // image's left or right edge. Branch-free, like the pixel test it follows.
  struct RowSums {
    int count = 0;
    std::int64_t sum_x = 0;
    int left_run = 0;                // line pixels fill columns [0, left_run)
    int run_begin = 0;               // first column of the run holding the latest line pixel
    int last = -2;                   // the latest line pixel's column
    int first_after_left_run = -1;   // the first line pixel's column past the left run
    int last_before_run_begin = -2;  // the last line pixel's column before run_begin
    int first = -1;                  // the first line pixel's column
    int runs = 0;
    void add(int x, bool is_line) {
      count += is_line ? 1 : 0;
      sum_x += is_line ? x : 0;
      first_after_left_run =
          (is_line && x != left_run && first_after_left_run < 0) ? x : first_after_left_run;
      left_run += (is_line && x == left_run) ? 1 : 0;
      const bool new_run = is_line && x != last + 1;
      runs += new_run ? 1 : 0;
      first = (is_line && first < 0) ? x : first;
      last_before_run_begin = new_run ? last : last_before_run_begin;
      run_begin = new_run ? x : run_begin;
      last = is_line ? x : last;
    }
  };

  // Sums over a blob's rows of each row's extent (from its first pixel's left edge to its last
  // pixel's right edge), for the blob's width across its direction on the floor. Where the image's
  // side edge cuts the blob the extent is what is seen of it, less than its width.
  struct RowExtents {
    int rows = 0;
    double width = 0.0, row = 0.0, row_squared = 0.0, middle = 0.0, row_middle = 0.0;
    void add(double y, double left, double right) {
      const double mid = 0.5 * (left + right);
      ++rows;
      width += right - left;
      row += y;
      row_squared += y * y;
      middle += mid;
      row_middle += y * mid;
    }
  };

  // The moments of a band's line pixels, divided by 255, and the rows that hold any; the same
  // moments of the pixels in whole runs (BandMeasurement::centre_x).
  struct BandSums {
    std::int64_t count = 0, sum_x = 0, sum_y = 0;
    int occupied_rows = 0;
    std::int64_t whole_count = 0, whole_sum_x = 0, whole_sum_y = 0;
    std::vector<BandMeasurement::RowSpan> spans;
    RowExtents extents;  // of all its rows, as if one blob
    // False once the rows' runs cannot all be one 8-connected blob: a row with two runs, a row
    // whose run does not touch the run in the row above, or line pixels again after an empty row.
    bool one_blob = true;
    bool previous_row_occupied = false;
    int previous_first = 0, previous_last = 0;
    void addRow(int y, const RowSums& row, int image_width);
  };

  BandMeasurement measureBand(const cv::Mat& bgr, const BandConfig& band,
                              std::optional<double> expected_x) const;
  // The floor test for rows [row_begin, row_end) (LineDetectorConfig::floor_margin): the band's
  // threshold (0 without the test; above 255 nothing passes), each column block's, and, where a
  // block is lit while the band is in shadow, that block's threshold (lit_threshold at
  // lit_light) scaled to each pixel's brightness, up to lit_light.
  struct FloorTest {
    int min_yellowness = 0;
    std::vector<int> block_min_yellowness;
    int lit_light = 0;  // 0: no lit block
    int lit_threshold = 0;
    // Pixels dimmer than three quarters of lit_light are not of the lit floor.
    bool passesAtItsBrightness(int brightness, int yellow) const {
      return 4 * brightness < 3 * lit_light ||
             yellow * lit_light >= lit_threshold * std::min(brightness, lit_light);
    }
  };
  FloorTest floorTest(const cv::Mat& bgr, int row_begin, int row_end) const;
  // Whether a blob of these row extents is too wide on the floor to be the line
  // (LineDetectorConfig::line_width_factor); false where its width cannot be measured.
  struct FloorScale;
  bool tooWide(const RowExtents& extents, const std::optional<FloorScale>& scale) const;
  std::optional<FloorScale> floorScale(const BandMeasurement& band) const;
  // The band's 8-connected blobs of line pixels, found from each row's runs (cheaper than
  // labelling a mask: a band holds a few dozen runs).
  struct Blobs;
  // The blob nearest expected_x among the `candidates` (as a mask over the blobs): of those
  // whose columns come nearest it, the largest, so a speck of noise beside the line does not win.
  static std::vector<bool> nearestBlob(const Blobs& blobs, const std::vector<bool>& candidates,
                                       double expected_x);
  // The `candidates` blob_saturation_fraction keeps.
  std::vector<bool> saturatedBlobs(const cv::Mat& bgr, const Blobs& blobs,
                                   const std::vector<bool>& candidates) const;
  void fillBand(const BandSums& sums, int image_width, BandMeasurement* result) const;

  LineDetectorConfig config_;
  CameraGeometry camera_;
  HsvBox box_;
};

}  // namespace follow_bot
