#include "follow_bot/line_detector.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

namespace follow_bot {
namespace {

// Largest band height accepted; keeps row arithmetic far from int overflow.
constexpr int kMaxBandRows = 1 << 16;

// Whole runs in fewer rows than this (of a band at least this tall) are a line leaving the band
// through a side edge or ending in it, crossing the rows so obliquely that its direction over
// them is too uncertain to place its centre: on the 0.5 m level camera such sightings lay up to
// 9 mm off the line, and the path law's bridges started from them (replayed; 4 rows did as well).
constexpr int kMinCentreRows = 5;

// The floor test samples every this many columns of every this many rows of the band: ~800
// pixels of a 640-column, 20-row band, enough for the median and MAD to a level or two.
constexpr int kFloorSampleStride = 4;

const cv::Scalar kLinePixelColour(255, 0, 255);  // magenta
const cv::Scalar kBandColour(0, 255, 0);         // green
const cv::Scalar kLookAheadColour(255, 255, 0);  // cyan
const cv::Scalar kCentroidColour(0, 0, 255);     // red, as in the lecture
constexpr int kCentroidRadius = 20;              // the lecture's circle

bool inside(int x, int low, int high) { return low <= x && x <= high; }

// The floor test's channel: how much yellower than grey a pixel is, 0 for blue-ish ones.
int yellowness(int b, int g, int r) { return std::max(std::min(g, r) - b, 0); }

std::string checkColour(const char* name, const HsvColor& colour) {
  const int channels[] = {colour.h, colour.s, colour.v};
  const char* channel_names[] = {"h", "s", "v"};
  for (int i = 0; i < 3; ++i) {
    if (!inside(channels[i], 0, 255)) {
      return std::string(name) + "." + channel_names[i] + " must be in [0, 255], got " +
             std::to_string(channels[i]);
    }
  }
  return "";
}

std::string checkBand(const char* name, const BandConfig& band) {
  std::ostringstream message;
  if (!(std::isfinite(band.distance_m) && band.distance_m > 0.0)) {
    message << name << ".distance_m must be > 0, got " << band.distance_m;
  } else if (!inside(band.rows, 1, kMaxBandRows)) {
    message << name << ".rows must be in [1, " << kMaxBandRows << "], got " << band.rows;
  }
  return message.str();
}

// Why detect() cannot use this frame, or empty when it can.
std::string checkFrame(const cv::Mat& bgr) {
  if (bgr.empty()) return "empty image";
  if (bgr.dims != 2) return "expected a 2-D image, got " + std::to_string(bgr.dims) + " dims";
  if (bgr.type() != CV_8UC3) {
    return "expected an 8-bit 3-channel BGR image (CV_8UC3, bgr8), got " +
           cv::typeToString(bgr.type());
  }
  return "";
}

// The floor test's column blocks, each judged in its own light (LineDetectorConfig::
// floor_margin): wide enough that the line (~50 columns at the band) fills well under a quarter
// of one, a whole number of SIMD chunks.
constexpr int kShadeBlockColumns = 128;
static_assert(kShadeBlockColumns % 16 == 0, "a SIMD chunk of 16 pixels lies in one block");
// A block's light is the lower quartile of its brightness: floor, unless paint covers three
// quarters of it (paint is brighter than floor, so it could only raise the estimate).
constexpr int kShadeQuantilePercent = 25;
// The deepest shade a block's threshold is scaled to, as a divisor of the band's light: the
// margin stands clear of the floor's texture, which dims with the light, but also of sensor
// noise, which does not.
constexpr int kDeepestShadeDivisor = 2;
// A block this much brighter than the band is lit where the band is in shadow.
constexpr struct { int num, den; } kLitBlockFactor{3, 2};
// The band's brightness is its brightest samples' (this percentile of max(B, G, R)): white
// paint, lit floor or the line itself. At kFullBrightness and above (the dimmest of the 38
// labelled real bands as shot reads 123) the margin is floor_margin; below, the band is
// underexposed or in a shadow, every yellowness in it is dimmer, and the margin dims in
// proportion, down to a quarter of it (kDimmestMarginDivisor): paint in a whole-frame shadow at
// 30 % of the light reads ~45 levels yellower than its floor, at the full margin, while the
// floor's noise does not dim. A band with a lit block (kLitBlockFactor) keeps the full margin: a
// bright object in a shadow beside lit floor would otherwise dim the lit floor's margin too.
constexpr int kBrightnessPercentile = 99;
constexpr int kFullBrightness = 120;
constexpr int kDimmestMarginDivisor = 4;
// 255 * 65536 / brightness: a pixel's chroma (<= brightness) over its brightness in 255ths, its
// HSV saturation, is (chroma * kReciprocals[brightness]) >> 16, without a division.
const std::array<int, 256> kReciprocals = [] {
  std::array<int, 256> reciprocals{};
  for (int brightness = 1; brightness < 256; ++brightness) {
    reciprocals[brightness] = 255 * 65536 / brightness;
  }
  return reciprocals;
}();

// Calls visit(x, is_line) for the pixels of one BGR row that might be line pixels: in the box
// with yellowness >= the floor test's threshold for x's column block (each in [0, 255]). Every
// pixel not visited is certainly not one. Sixteen pixels at a time are screened in SIMD with
// HsvBox::Screen and the yellowness, exactly (most floor pixels fail); the survivors get the exact
// box test, whose verdict is passed on rather than branched on, because near the box edges it is a
// coin toss the branch predictor would lose.
template <typename FloorTest, typename Visit>
void visitCandidates(const HsvBox& box, const FloorTest& floor, const uchar* bgr_row, int cols,
                     Visit&& visit) {
  const std::vector<int>& block_min_yellowness = floor.block_min_yellowness;
  int x = 0;
#if CV_SIMD128
  cv::v_uint8x16 min_yellow;
  const HsvBox::Screen& screen = box.screen();
  const cv::v_uint8x16 min_value = cv::v_setall_u8(static_cast<uchar>(screen.min_value));
  const cv::v_uint8x16 max_value = cv::v_setall_u8(static_cast<uchar>(screen.max_value));
  const cv::v_uint16x8 min_saturation =
      cv::v_setall_u16(static_cast<ushort>(screen.min_saturation));
  const cv::v_uint16x8 max_saturation =
      cv::v_setall_u16(static_cast<ushort>(screen.max_saturation));
  const cv::v_uint16x8 zero = cv::v_setzero_u16();
  // min_saturation * max <= 255 * chroma <= max_saturation * max, on eight 16-bit lanes. The
  // 16-bit subtractions saturate at 0, so each is 0 exactly when its inequality holds.
  auto saturation_ok = [&](const cv::v_uint16x8& max, const cv::v_uint16x8& chroma) {
    const cv::v_uint16x8 chroma255 = cv::v_shl<8>(chroma) - chroma;
    return ((cv::v_mul_wrap(max, min_saturation) - chroma255) |
            (chroma255 - cv::v_mul_wrap(max, max_saturation))) == zero;
  };
  // HsvBox's shifted hue numerator on eight 16-bit lanes, with the same sector rule.
  auto hue_numerator = [](const cv::v_uint16x8& b, const cv::v_uint16x8& g, const cv::v_uint16x8& r,
                          const cv::v_uint16x8& max, const cv::v_uint16x8& chroma) {
    const cv::v_int16x8 sb = cv::v_reinterpret_as_s16(b), sg = cv::v_reinterpret_as_s16(g),
                        sr = cv::v_reinterpret_as_s16(r), smax = cv::v_reinterpret_as_s16(max);
    const cv::v_int16x8 c2 = cv::v_shl<1>(cv::v_reinterpret_as_s16(chroma));
    const cv::v_int16x8 c4 = c2 + c2;
    const cv::v_int16x8 n =
        cv::v_select(smax == sr, sg - sb, cv::v_select(smax == sg, sb - sr + c2, sr - sg + c4));
    return n + ((n < cv::v_setzero_s16()) & (c4 + c2));
  };
  for (; x + 16 <= cols; x += 16) {
    if (x % kShadeBlockColumns == 0) {
      min_yellow =
          cv::v_setall_u8(static_cast<uchar>(block_min_yellowness[x / kShadeBlockColumns]));
    }
    cv::v_uint8x16 b, g, r;
    cv::v_load_deinterleave(bgr_row + 3 * x, b, g, r);
    const cv::v_uint8x16 max = cv::v_max(cv::v_max(b, g), r);
    const cv::v_uint8x16 chroma = max - cv::v_min(cv::v_min(b, g), r);
    const cv::v_uint8x16 yellow = cv::v_min(g, r) - b;  // saturates at 0, as yellowness()
    cv::v_uint16x8 max_low, max_high, chroma_low, chroma_high;
    cv::v_expand(max, max_low, max_high);
    cv::v_expand(chroma, chroma_low, chroma_high);
    const cv::v_uint8x16 passed =
        (cv::v_min(cv::v_max(max, min_value), max_value) == max) &
        (cv::v_max(yellow, min_yellow) == yellow) &
        cv::v_pack(saturation_ok(max_low, chroma_low), saturation_ok(max_high, chroma_high));
    unsigned bits = cv::v_signmask(passed);
    if (bits == 0) continue;
    // Survivors: finish the decomposition for all sixteen lanes at once.
    cv::v_uint16x8 b_low, b_high, g_low, g_high, r_low, r_high;
    cv::v_expand(b, b_low, b_high);
    cv::v_expand(g, g_low, g_high);
    cv::v_expand(r, r_low, r_high);
    alignas(16) uchar max_lanes[16];
    alignas(16) uchar chroma_lanes[16];
    alignas(16) uchar yellow_lanes[16];
    alignas(16) short numerator_lanes[16];
    cv::v_store_aligned(max_lanes, max);
    cv::v_store_aligned(chroma_lanes, chroma);
    cv::v_store_aligned(yellow_lanes, yellow);
    cv::v_store_aligned(numerator_lanes, hue_numerator(b_low, g_low, r_low, max_low, chroma_low));
    cv::v_store_aligned(numerator_lanes + 8,
                        hue_numerator(b_high, g_high, r_high, max_high, chroma_high));
    for (; bits != 0; bits &= bits - 1) {
      const int lane = ::trailingZeros32(bits);
      // & on ints, not &&: branch-free (a coin toss near the box edges, see above).
      const int in_box =
          box.containsDecomposed(max_lanes[lane], chroma_lanes[lane], numerator_lanes[lane]);
      visit(x + lane,
            (in_box & floor.passesAtItsBrightness(max_lanes[lane], yellow_lanes[lane])) != 0);
    }
  }
#endif
  for (const uchar* pixel = bgr_row + 3 * x; x < cols; ++x, pixel += 3) {
    const int yellow = yellowness(pixel[0], pixel[1], pixel[2]);
    const int in_box = box.contains(pixel[0], pixel[1], pixel[2]);
    const int yellow_enough = yellow >= block_min_yellowness[x / kShadeBlockColumns];
    visit(x, (in_box & yellow_enough &
              floor.passesAtItsBrightness(std::max({pixel[0], pixel[1], pixel[2]}), yellow)) != 0);
  }
}

const LineDetectorConfig& validated(const LineDetectorConfig& config,
                                    const CameraGeometry& camera) {
  for (const std::string& error : {validate(config), validate(camera)}) {
    if (!error.empty()) throw std::invalid_argument("LineDetector: " + error);
  }
  return config;
}

void drawBand(cv::Mat& bgr, const BandMeasurement& band, const cv::Scalar& outline,
              int centroid_thickness) {
  if (band.row_end > band.row_begin) {
    cv::rectangle(bgr, cv::Point(0, band.row_begin), cv::Point(bgr.cols - 1, band.row_end - 1),
                  outline, 1);
  }
  if (band.pixel_count > 0) {
    cv::circle(bgr, cv::Point(cvRound(band.centroid_x), cvRound(band.centroid_y)), kCentroidRadius,
               kCentroidColour, centroid_thickness);
  }
}

}  // namespace

std::string validate(const LineDetectorConfig& config) {
  for (const std::string& error :
       {checkColour("lower", config.lower), checkColour("upper", config.upper),
        checkBand("band", config.band), checkBand("look_ahead", config.look_ahead)}) {
    if (!error.empty()) return error;
  }
  std::ostringstream message;
  const int lower[] = {config.lower.h, config.lower.s, config.lower.v};
  const int upper[] = {config.upper.h, config.upper.s, config.upper.v};
  const char* names[] = {"h", "s", "v"};
  for (int i = 0; i < 3; ++i) {
    if (lower[i] > upper[i]) {
      message << "lower." << names[i] << " (" << lower[i] << ") must be <= upper." << names[i]
              << " (" << upper[i] << "); the box would match nothing";
      return message.str();
    }
  }
  if (config.look_ahead_enabled && !(config.look_ahead.distance_m > config.band.distance_m)) {
    message << "look_ahead.distance_m (" << config.look_ahead.distance_m
            << ") must be beyond band.distance_m (" << config.band.distance_m << ")";
    return message.str();
  }
  return checkFields(config);
}

LineDetector::LineDetector(const LineDetectorConfig& config, const CameraGeometry& camera)
    : config_(validated(config, camera)), camera_(camera), box_(config.lower, config.upper) {}

LineMeasurement LineDetector::detect(const cv::Mat& bgr) const {
  return detect(bgr, LineMeasurement());
}

LineMeasurement LineDetector::detect(const cv::Mat& bgr, const LineMeasurement& previous) const {
  LineMeasurement measurement;
  measurement.error = checkFrame(bgr);
  if (!measurement.ok()) return measurement;
  measurement.image_width = bgr.cols;
  measurement.image_height = bgr.rows;
  // A previous sighting is only a hint for a frame of the same size.
  const bool same_size = previous.image_width == bgr.cols && previous.image_height == bgr.rows;
  auto expected_x = [&](const BandMeasurement& band) {
    return same_size && band.found ? std::optional<double>(band.centroid_x) : std::nullopt;
  };
  measurement.band = measureBand(bgr, config_.band, expected_x(previous.band));
  if (config_.look_ahead_enabled) {
    measurement.look_ahead = measureBand(bgr, config_.look_ahead, expected_x(previous.look_ahead));
  }
  return measurement;
}

// The floor's scale at a band's centre row: along a row the image is the floor scaled (a row
// sees the floor at one depth), by metres_per_column, which changes from row to row; a row
// further down sees the floor metres_per_row nearer.
struct LineDetector::FloorScale {
  double centre_column = 0.0;
  double metres_per_column = 0.0;
  double change_per_row = 0.0;  // of metres_per_column
  double metres_per_row = 0.0;
};

// Line pixels of a band, row by row, grouped into 8-connected blobs.
struct LineDetector::Blobs {
  struct Run {
    int row = 0;             // image row
    int begin = 0, end = 0;  // columns [begin, end]
    int blob = 0;            // index of its root run until resolved, then of its blob
  };
  std::vector<Run> runs;  // by row, then column
  int row_begin = 0, row_end = 0, image_width = 0;
  int count = 0;  // blobs
  std::vector<int> area, first_column, last_column;
  std::vector<RowExtents> extents;

  // `columns`: each row's line pixels in increasing order, rows [row_begin, row_end) after each
  // other, `row_starts[i]` where row row_begin + i starts (one more entry at the end).
  Blobs(const cv::Mat& bgr, const int* columns, const std::vector<int>& row_starts, int first_row)
      : row_begin(first_row),
        row_end(first_row + static_cast<int>(row_starts.size()) - 1),
        image_width(bgr.cols) {
    std::vector<int> parent;
    auto root = [&](int run) {
      while (parent[run] != run) run = parent[run] = parent[parent[run]];
      return run;
    };
    size_t previous_row_first = 0;  // the previous row's first run
    for (int y = row_begin; y < row_end; ++y) {
      const size_t row_first = runs.size();
      // Each stretch of consecutive columns is a run.
      const int* column = columns + row_starts[y - row_begin];
      const int* const row_end_column = columns + row_starts[y - row_begin + 1];
      while (column != row_end_column) {
        const int begin = *column;
        int end = begin;
        while (++column != row_end_column && *column == end + 1) ++end;
        runs.push_back({y, begin, end, static_cast<int>(runs.size())});
        parent.push_back(runs.back().blob);
      }
      // Runs of adjacent rows touch when their columns overlap or meet at a corner.
      for (size_t above = previous_row_first, here = row_first;
           above < row_first && here < runs.size();) {
        if (runs[above].end + 1 >= runs[here].begin && runs[here].end + 1 >= runs[above].begin) {
          const int a = root(static_cast<int>(above)), b = root(static_cast<int>(here));
          parent[std::max(a, b)] = std::min(a, b);
        }
        (runs[above].end < runs[here].end) ? ++above : ++here;
      }
      previous_row_first = row_first;
    }
    // Blobs numbered in the order of their first run, as a raster scan meets them.
    std::vector<int> blob_of_root(runs.size(), -1);
    for (size_t i = 0; i < runs.size(); ++i) {
      const int r = root(static_cast<int>(i));
      if (blob_of_root[r] < 0) {
        blob_of_root[r] = count++;
        area.push_back(0);
        first_column.push_back(runs[i].begin);
        last_column.push_back(runs[i].end);
        extents.emplace_back();
      }
      Run& run = runs[i];
      run.blob = blob_of_root[r];
      area[run.blob] += run.end - run.begin + 1;
      first_column[run.blob] = std::min(first_column[run.blob], run.begin);
      last_column[run.blob] = std::max(last_column[run.blob], run.end);
    }
    // Each blob's extent in each of its rows: its runs in a row come in column order.
    std::vector<int> open_row(count, -1), open_first(count), open_last(count);
    auto close_row = [&](int blob) {
      extents[blob].add(open_row[blob], open_first[blob] - 0.5, open_last[blob] + 0.5);
    };
    for (const Run& run : runs) {
      if (open_row[run.blob] != run.row) {
        if (open_row[run.blob] >= 0) close_row(run.blob);
        open_row[run.blob] = run.row;
        open_first[run.blob] = run.begin;
      }
      open_last[run.blob] = run.end;
    }
    for (int blob = 0; blob < count; ++blob) close_row(blob);
  }

  // Each blob's sum over its pixels of HSV's S, in 255ths.
  std::vector<std::int64_t> saturationSums(const cv::Mat& bgr) const {
    std::vector<std::int64_t> sums(count, 0);
    for (const Run& run : runs) {
      const uchar* pixel = bgr.ptr<uchar>(run.row) + 3 * run.begin;
      std::int64_t sum = 0;
      for (int x = run.begin; x <= run.end; ++x, pixel += 3) {
        const uchar brightness = std::max({pixel[0], pixel[1], pixel[2]});
        sum +=
            ((brightness - std::min({pixel[0], pixel[1], pixel[2]})) * kReciprocals[brightness]) >>
            16;
      }
      sums[run.blob] += sum;
    }
    return sums;
  }

  // The band's sums over the pixels of the kept blobs.
  BandSums sums(const std::vector<bool>& kept) const {
    BandSums result;
    size_t next = 0;
    for (int y = row_begin; y < row_end; ++y) {
      RowSums row;
      for (; next < runs.size() && runs[next].row == y; ++next) {
        if (!kept[runs[next].blob]) continue;
        for (int x = runs[next].begin; x <= runs[next].end; ++x) row.add(x, true);
      }
      result.addRow(y, row, image_width);
    }
    return result;
  }
};

BandMeasurement LineDetector::measureBand(const cv::Mat& bgr, const BandConfig& band,
                                          std::optional<double> expected_x) const {
  BandMeasurement result;
  const BandPlacement placement = placeBand(camera_, band, bgr.rows);
  result.row_begin = placement.row_begin;
  result.row_end = placement.row_end;
  result.distance_m = placement.distance_m;
  result.clamped = placement.clamped;
  const int band_rows = result.row_end - result.row_begin;
  const FloorTest floor = floorTest(bgr, result.row_begin, result.row_end);
  result.min_yellowness = floor.min_yellowness;
  result.block_min_yellowness = floor.block_min_yellowness;
  if (result.min_yellowness > 255) return result;  // the floor is as yellow as paint gets

  // Each row's line pixel columns, kept in case a blob has to be picked out of the band. Every
  // candidate is written and only line pixels advance the end: no branch on the coin toss.
  const bool gate_widths = config_.line_width_factor > 0.0;
  const bool may_pick =
      (expected_x || config_.blob_saturation_fraction > 0.0 || gate_widths) && band_rows > 0;
  // Left uninitialised: only the entries below `end` are ever read.
  const std::unique_ptr<int[]> columns(may_pick ? new int[static_cast<size_t>(band_rows) * bgr.cols]
                                                : nullptr);
  std::vector<int> row_starts(may_pick ? band_rows + 1 : 0, 0);
  int end = 0;

  // The lecture's moments, divided by 255: m00 = count, m10 = sum_x, m01 = sum_y.
  BandSums sums;
  for (int y = result.row_begin; y < result.row_end; ++y) {
    RowSums row;
    if (may_pick) {
      visitCandidates(box_, floor, bgr.ptr<uchar>(y), bgr.cols, [&](int x, bool is_line) {
        row.add(x, is_line);
        columns[end] = x;
        end += is_line ? 1 : 0;
      });
      row_starts[y - result.row_begin + 1] = end;
    } else {
      visitCandidates(box_, floor, bgr.ptr<uchar>(y), bgr.cols,
                      [&](int x, bool is_line) { row.add(x, is_line); });
    }
    sums.addRow(y, row, bgr.cols);
  }
  const std::optional<FloorScale> scale =
      gate_widths && sums.count > 0 ? floorScale(result) : std::nullopt;
  if (may_pick && !sums.one_blob) {
    const Blobs blobs(bgr, columns.get(), row_starts, result.row_begin);
    std::vector<bool> candidates(blobs.count);
    for (int blob = 0; blob < blobs.count; ++blob) {
      candidates[blob] = !tooWide(blobs.extents[blob], scale);
    }
    const std::vector<bool> kept = expected_x ? nearestBlob(blobs, candidates, *expected_x)
                                              : saturatedBlobs(bgr, blobs, candidates);
    int largest = 0;
    for (int blob = 0; blob < blobs.count; ++blob) {
      largest = std::max(largest, kept[blob] ? blobs.area[blob] : 0);
    }
    if (std::find(kept.begin(), kept.end(), false) != kept.end()) sums = blobs.sums(kept);
    fillBand(sums, bgr.cols, &result);
    // Specks (of floor between blobs the gates left out, or noise) add up to no line.
    result.found = result.found && largest >= config_.min_pixels;
    return result;
  }
  if (tooWide(sums.extents, scale)) sums = BandSums();
  fillBand(sums, bgr.cols, &result);
  return result;
}

LineDetector::FloorTest LineDetector::floorTest(const cv::Mat& bgr, int row_begin,
                                                int row_end) const {
  const int blocks = (bgr.cols + kShadeBlockColumns - 1) / kShadeBlockColumns;
  FloorTest test;
  test.block_min_yellowness.assign(blocks, 0);
  if (config_.floor_margin == 0) return test;
  // Each block's samples' max(B, G, R) and yellowness, in stretches of their own of one
  // allocation. Every block has some whenever the band has: its first column is sampled.
  const int rows_sampled = (row_end - row_begin + kFloorSampleStride - 1) / kFloorSampleStride;
  const int block_capacity = std::max(rows_sampled, 0) * (kShadeBlockColumns / kFloorSampleStride);
  const size_t capacity = static_cast<size_t>(blocks) * block_capacity;
  const std::unique_ptr<uchar[]> sample_lights(new uchar[capacity]);
  const std::unique_ptr<uchar[]> sample_yellows(new uchar[capacity]);
  std::vector<int> block_sizes(blocks, 0);
  for (int y = row_begin; y < row_end; y += kFloorSampleStride) {
    const uchar* row = bgr.ptr<uchar>(y);
    for (int block = 0; block < blocks; ++block) {
      const size_t first = static_cast<size_t>(block) * block_capacity + block_sizes[block];
      uchar* lights = sample_lights.get() + first;
      uchar* yellows = sample_yellows.get() + first;
      const int end = std::min((block + 1) * kShadeBlockColumns, bgr.cols);
      int taken = 0;
      for (int x = block * kShadeBlockColumns; x < end; x += kFloorSampleStride, ++taken) {
        const uchar* pixel = row + 3 * x;
        lights[taken] = std::max({pixel[0], pixel[1], pixel[2]});
        yellows[taken] = static_cast<uchar>(yellowness(pixel[0], pixel[1], pixel[2]));
      }
      block_sizes[block] += taken;
    }
  }
  int samples = 0;
  for (int size : block_sizes) samples += size;
  if (samples == 0) return test;
  // Each block's light (the brightness at its lower quartile) and its floor's yellowness in that
  // light (the median over the darkest quarter); the band's light is the median block's, so
  // that a shadow over fewer than half the blocks leaves it that of the lit floor.
  std::vector<int> block_light(blocks), block_floor(blocks);
  std::array<int, 256> light_counts{};  // the band's, for its brightness
  for (int block = 0; block < blocks; ++block) {
    const size_t first = static_cast<size_t>(block) * block_capacity;
    const uchar* lights = sample_lights.get() + first;
    const uchar* yellows = sample_yellows.get() + first;
    const int size = block_sizes[block];
    // Counting, not sorting: a few hundred samples into 256 levels.
    std::array<int, 256> counts{};
    for (int i = 0; i < size; ++i) ++counts[lights[i]];
    for (int level = 0; level < 256; ++level) light_counts[level] += counts[level];
    int light = 0;
    for (int below = counts[0]; below <= size * kShadeQuantilePercent / 100;) {
      below += counts[++light];
    }
    block_light[block] = light;
    counts.fill(0);
    int darkest = 0;
    for (int i = 0; i < size; ++i) {
      const bool dark = lights[i] <= light;
      counts[yellows[i]] += dark;
      darkest += dark;
    }
    int floor_yellowness = 0;
    for (int below = counts[0]; below <= darkest / 2;) below += counts[++floor_yellowness];
    block_floor[block] = floor_yellowness;
  }
  std::vector<int> sorted_light = block_light;
  const auto middle = sorted_light.begin() + blocks / 2;
  std::nth_element(sorted_light.begin(), middle, sorted_light.end());
  const int band_light = *middle;
  // The floor's yellowness as it would read in the band's light: each block's samples scaled by
  // the band's light over the block's, so that lit floor beside a shadow (or shadowed floor in a
  // lit band) joins one mode and neither the median nor the MAD measures the shadow's contrast.
  std::array<int, 256> histogram{};
  for (int block = 0; block < blocks; ++block) {
    const uchar* yellows = sample_yellows.get() + static_cast<size_t>(block) * block_capacity;
    const int light = std::max(block_light[block], band_light / kDeepestShadeDivisor);
    // Fixed point, 8 fractional bits, truncated to whole levels; a block as lit as the band reads
    // exactly as before, and in a black band every sample does.
    const int scale = light > 0 ? (band_light << 8) / light : 1 << 8;
    for (int i = 0; i < block_sizes[block]; ++i) {
      ++histogram[std::min((yellows[i] * scale) >> 8, 255)];
    }
  }
  const int half = (samples + 1) / 2;
  int median = 0;
  for (int below = histogram[0]; below < half;) below += histogram[++median];
  // The median absolute deviation: the smallest d with half the samples within median +- d.
  int mad = 0;
  for (int within = histogram[median]; within < half;) {
    ++mad;
    within += (median - mad >= 0 ? histogram[median - mad] : 0) +
              (median + mad <= 255 ? histogram[median + mad] : 0);
  }
  // The band's brightness (kBrightnessPercentile).
  int brightness = 0;
  for (int below = light_counts[0]; below < samples * kBrightnessPercentile / 100;) {
    below += light_counts[++brightness];
  }
  const int dimmed_margin = std::max(
      (config_.floor_margin * std::min(brightness, kFullBrightness) + kFullBrightness - 1) /
          kFullBrightness,
      config_.floor_margin / kDimmestMarginDivisor);
  const auto is_lit = [&](int light) {
    return kLitBlockFactor.den * light >= kLitBlockFactor.num * band_light;
  };
  // A block lit beside a shadow: the band is not dim, part of it is shaded.
  const bool any_lit = std::any_of(block_light.begin(), block_light.end(), is_lit);
  const int margin = std::max(any_lit ? config_.floor_margin : dimmed_margin,
                              static_cast<int>(std::ceil(config_.floor_mads * mad)));
  test.min_yellowness = median + margin;
  if (band_light == 0) {  // a black band: no light to scale by
    test.block_min_yellowness.assign(blocks, test.min_yellowness);
    return test;
  }
  for (int block = 0; block < blocks; ++block) {
    const int light = std::clamp(block_light[block], band_light / kDeepestShadeDivisor, band_light);
    // The band's threshold and the margin over the block's own dark floor, both in the block's
    // light (rounded up: a block as lit as the band keeps the band's threshold exactly); the
    // larger, so that a block darker only beside a bright object (a red stop line across the
    // band) keeps its floor out. Never above the band's: paint filling a block must not raise it.
    const int scaled = (test.min_yellowness * light + band_light - 1) / band_light;
    const int own_floor = block_floor[block] + (margin * light + band_light - 1) / band_light;
    test.block_min_yellowness[block] = std::min(test.min_yellowness, std::max(scaled, own_floor));
    // A lit block in a band mostly in shadow: its floor's test, in proportion to each pixel's
    // brightness, holds over the whole band. A block is lit floor when its floor is no yellower
    // than the band's would be in its light, by the margin: paint filling it is far yellower.
    // Of several, the most lenient.
    const int lit_threshold = block_floor[block] + margin;
    const bool floor_in_more_light =
        block_floor[block] * band_light <= median * block_light[block] + margin * band_light;
    if (is_lit(block_light[block]) && floor_in_more_light &&
        (test.lit_light == 0 ||
         lit_threshold * test.lit_light < test.lit_threshold * block_light[block])) {
      test.lit_light = block_light[block];
      test.lit_threshold = lit_threshold;
    }
  }
  return test;
}

std::optional<LineDetector::FloorScale> LineDetector::floorScale(
    const BandMeasurement& band) const {
  const double centre_row = 0.5 * (band.row_begin + band.row_end - 1);
  const double u = camera_.cx;
  const std::optional<cv::Point2d> above = pixelToGround(camera_, u, centre_row - 0.5);
  const std::optional<cv::Point2d> below = pixelToGround(camera_, u, centre_row + 0.5);
  const std::optional<cv::Point2d> above_right = pixelToGround(camera_, u + 1.0, centre_row - 0.5);
  const std::optional<cv::Point2d> below_right = pixelToGround(camera_, u + 1.0, centre_row + 0.5);
  if (!above || !below || !above_right || !below_right) return std::nullopt;
  const double above_scale = std::abs(above_right->y - above->y);
  const double below_scale = std::abs(below_right->y - below->y);
  return FloorScale{u, 0.5 * (above_scale + below_scale), below_scale - above_scale,
                    std::abs(above->x - below->x)};
}

bool LineDetector::tooWide(const RowExtents& extents,
                           const std::optional<FloorScale>& scale) const {
  // Over fewer rows the blob's direction, and so its width across it, is not measured.
  if (!scale || extents.rows < kMinCentreRows) return false;
  const double n = extents.rows;
  const double mean_row = extents.row / n;
  const double mean_middle = extents.middle / n;
  // The blob's direction: its rows' middles' drift per row, a least-squares line, taken onto the
  // floor, where a row's columns shift by the drift and by the row's change of scale.
  const double drift = (extents.row_middle / n - mean_row * mean_middle) /
                       (extents.row_squared / n - mean_row * mean_row);
  const double across_per_row = drift * scale->metres_per_column +
                                (mean_middle - scale->centre_column) * scale->change_per_row;
  const double slope = across_per_row / scale->metres_per_row;
  // A run cuts the blob along the row; across its direction it is cos(atan(slope)) as wide.
  const double width =
      extents.width / n * scale->metres_per_column / std::sqrt(1.0 + slope * slope);
  return width > config_.line_width_factor * config_.line_width_m;
}

std::vector<bool> LineDetector::nearestBlob(const Blobs& blobs, const std::vector<bool>& candidates,
                                            double expected_x) {
  int best = -1;
  double best_distance = 0.0;
  for (int blob = 0; blob < blobs.count; ++blob) {
    if (!candidates[blob]) continue;
    const double distance = std::max(
        {0.0, blobs.first_column[blob] - expected_x, expected_x - blobs.last_column[blob]});
    if (best < 0 || distance < best_distance ||
        (distance == best_distance && blobs.area[blob] > blobs.area[best])) {
      best = blob;
      best_distance = distance;
    }
  }
  std::vector<bool> kept(blobs.count, false);
  if (best >= 0) kept[best] = true;
  return kept;
}

std::vector<bool> LineDetector::saturatedBlobs(const cv::Mat& bgr, const Blobs& blobs,
                                               const std::vector<bool>& candidates) const {
  const std::vector<std::int64_t> saturation = blobs.saturationSums(bgr);
  std::vector<double> mean_saturation(blobs.count);
  double strongest = 0.0, strongest_line_sized = 0.0;
  for (int blob = 0; blob < blobs.count; ++blob) {
    if (!candidates[blob]) continue;
    mean_saturation[blob] = static_cast<double>(saturation[blob]) / blobs.area[blob];
    strongest = std::max(strongest, mean_saturation[blob]);
    if (blobs.area[blob] >= config_.min_pixels) {
      strongest_line_sized = std::max(strongest_line_sized, mean_saturation[blob]);
    }
  }
  const double bar = config_.blob_saturation_fraction *
                     (strongest_line_sized > 0.0 ? strongest_line_sized : strongest);
  std::vector<bool> kept(blobs.count);
  for (int blob = 0; blob < blobs.count; ++blob) {
    kept[blob] = candidates[blob] && mean_saturation[blob] >= bar;
  }
  return kept;
}

void LineDetector::BandSums::addRow(int y, const RowSums& row, int image_width) {
  if (row.count > 0) {
    extents.add(y, row.first - 0.5, row.last + 0.5);
    const bool touches_previous =
        previous_row_occupied && row.first <= previous_last + 1 && row.last >= previous_first - 1;
    one_blob = one_blob && row.runs == 1 && (count == 0 || touches_previous);
    previous_first = row.first;
    previous_last = row.last;
  }
  previous_row_occupied = row.count > 0;
  count += row.count;
  sum_x += row.sum_x;
  sum_y += static_cast<std::int64_t>(row.count) * y;
  occupied_rows += row.count > 0 ? 1 : 0;
  // The cut runs: columns [0, left_run) and [right_begin, image_width); a run across the
  // whole row is the left one.
  const int right_begin =
      row.last == image_width - 1 ? std::max(row.run_begin, row.left_run) : image_width;
  const auto column_sum = [](std::int64_t begin, std::int64_t end) {
    return (begin + end - 1) * (end - begin) / 2;
  };
  const int whole = row.count - row.left_run - (image_width - right_begin);
  if (whole > 0) {
    // The first pixel past the left run is whole (a right run comes last); so is the last one
    // before a right run.
    const int last_whole = right_begin < image_width ? row.last_before_run_begin : row.last;
    spans.push_back({static_cast<double>(y), row.first_after_left_run - 0.5, last_whole + 0.5});
  }
  whole_count += whole;
  whole_sum_x += row.sum_x - column_sum(0, row.left_run) - column_sum(right_begin, image_width);
  whole_sum_y += static_cast<std::int64_t>(whole) * y;
}

void LineDetector::fillBand(const BandSums& sums, int image_width, BandMeasurement* result) const {
  result->spans = sums.spans;
  result->centre_pixel_count = static_cast<int>(sums.whole_count);
  if (sums.whole_count > 0) {
    const int band_rows = result->row_end - result->row_begin;
    result->centre_found =
        sums.whole_count >= config_.min_pixels &&
        static_cast<int>(sums.spans.size()) >= std::min(kMinCentreRows, band_rows);
    result->centre_x = static_cast<double>(sums.whole_sum_x) / sums.whole_count;
    result->centre_y = static_cast<double>(sums.whole_sum_y) / sums.whole_count;
  }
  result->pixel_count = static_cast<int>(sums.count);
  if (sums.count == 0) return;

  result->found = sums.count >= config_.min_pixels;
  result->centroid_x = static_cast<double>(sums.sum_x) / sums.count;
  result->centroid_y = static_cast<double>(sums.sum_y) / sums.count;
  const double half_width = image_width / 2.0;
  result->error_px = result->centroid_x - half_width;
  result->error_normalised = result->error_px / half_width;

  const double row_coverage =
      static_cast<double>(sums.occupied_rows) / (result->row_end - result->row_begin);
  const double width_fraction = static_cast<double>(sums.count) / sums.occupied_rows / image_width;
  const double width_sanity = width_fraction <= config_.max_width_fraction
                                  ? 1.0
                                  : (1.0 - width_fraction) / (1.0 - config_.max_width_fraction);
  result->confidence = row_coverage * width_sanity;
}

cv::Mat LineDetector::debugMask(const cv::Mat& bgr) const {
  if (!checkFrame(bgr).empty()) return cv::Mat();
  cv::Mat mask(bgr.size(), CV_8UC1, cv::Scalar::all(0));
  auto mark_band = [&](const BandConfig& band) {
    const BandPlacement placement = placeBand(camera_, band, bgr.rows);
    const FloorTest floor = floorTest(bgr, placement.row_begin, placement.row_end);
    if (floor.min_yellowness > 255) return;
    for (int y = placement.row_begin; y < placement.row_end; ++y) {
      uchar* mask_row = mask.ptr<uchar>(y);
      visitCandidates(box_, floor, bgr.ptr<uchar>(y), bgr.cols,
                      [&](int x, bool is_line) { mask_row[x] = is_line ? 255 : 0; });
    }
  };
  mark_band(config_.band);
  if (config_.look_ahead_enabled) mark_band(config_.look_ahead);
  return mask;
}

bool LineDetector::drawDebug(cv::Mat& bgr, const LineMeasurement& measurement) const {
  if (!checkFrame(bgr).empty() || bgr.cols != measurement.image_width ||
      bgr.rows != measurement.image_height) {
    return false;
  }
  bgr.setTo(kLinePixelColour, debugMask(bgr));
  drawBand(bgr, measurement.band, kBandColour, cv::FILLED);
  if (config_.look_ahead_enabled) drawBand(bgr, measurement.look_ahead, kLookAheadColour, 2);
  return true;
}

}  // namespace follow_bot
