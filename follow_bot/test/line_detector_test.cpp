#include "follow_bot/line_detector.h"

#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>
#include <vector>

#include "follow_bot/common.h"
#include "follow_bot_common/testing/harness_camera.h"

namespace follow_bot {
namespace {

const cv::Scalar kGrey(110, 115, 120);
const cv::Scalar kYellow(0, 220, 230);  // BGR; OpenCV HSV (29, 255, 230)
const HsvColor kLectureLower{20, 100, 100};
const HsvColor kLectureUpper{30, 255, 255};

cv::Mat greyFrame(int rows = 480, int cols = 640) { return cv::Mat(rows, cols, CV_8UC3, kGrey); }

// Paints columns [x, x + width) of rows [top, bottom) yellow.
void paintStripe(cv::Mat& frame, int x, int width, int top, int bottom) {
  frame(cv::Range(top, bottom), cv::Range(x, x + width)).setTo(kYellow);
}

struct Stripe {
  int x, width, top, bottom;
};

// A grey frame with these stripes painted (paintStripe).
cv::Mat stripedFrame(std::initializer_list<Stripe> stripes) {
  cv::Mat frame = greyFrame();
  for (const Stripe& s : stripes) paintStripe(frame, s.x, s.width, s.top, s.bottom);
  return frame;
}

// The lecture's mask: full-frame HSV, inRange, every row outside the band (as placed for the
// default camera) zeroed.
cv::Mat referenceMask(const cv::Mat& bgr, const LineDetectorConfig& config) {
  cv::Mat hsv, mask;
  cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
  cv::inRange(hsv, cv::Scalar(config.lower.h, config.lower.s, config.lower.v),
              cv::Scalar(config.upper.h, config.upper.s, config.upper.v), mask);
  const BandPlacement band = placeBand(CameraGeometry(), config.band, bgr.rows);
  const int top = band.row_begin;
  const int bottom = band.row_end;
  for (int y = 0; y < bgr.rows; ++y) {
    if (y < top || y >= bottom) mask.row(y).setTo(0);
  }
  return mask;
}

// Bound sets for the equivalence tests: the lecture's, and edge cases of every channel.
std::vector<std::pair<HsvColor, HsvColor>> boundSets() {
  return {
      {kLectureLower, kLectureUpper},     {{0, 0, 0}, {179, 255, 255}},  // everything
      {{0, 0, 0}, {0, 255, 255}},          // H = 0 only, which includes hues rounding to 180
      {{179, 0, 0}, {179, 255, 255}},      // H = 179 only
      {{0, 0, 0}, {10, 255, 255}},         // red, low side
      {{170, 50, 0}, {179, 255, 255}},     // red, high side
      {{0, 0, 0}, {179, 0, 255}},          // greys only (S = 0)
      {{0, 255, 255}, {179, 255, 255}},    // fully saturated and bright only
      {{0, 0, 0}, {179, 255, 0}},          // black only (V = 0)
      {{150, 255, 255}, {150, 255, 255}},  // a single HSV point at a sector boundary
      {{1, 1, 1}, {178, 254, 254}},        // everything but the extremes
      {{90, 60, 40}, {130, 200, 220}},     // blue, inner bounds on S and V
      {{0, 0, 0}, {255, 255, 255}},        // H upper above 179 behaves as 179
  };
}

// The lecture's pipeline: its colour box, no floor test or width gate, and every line pixel in
// the band counts, however many blobs they form.
LineDetectorConfig lectureConfig() {
  LineDetectorConfig config;
  config.lower = kLectureLower;
  config.upper = kLectureUpper;
  config.floor_margin = 0;
  config.line_width_factor = 0.0;
  config.blob_saturation_fraction = 0.0;
  return config;
}

LineDetectorConfig withBounds(const HsvColor& lower, const HsvColor& upper) {
  LineDetectorConfig config = lectureConfig();
  config.lower = lower;
  config.upper = upper;
  return config;
}

std::string describe(const HsvColor& lower, const HsvColor& upper) {
  return "H " + std::to_string(lower.h) + "-" + std::to_string(upper.h) + " S " +
         std::to_string(lower.s) + "-" + std::to_string(upper.s) + " V " + std::to_string(lower.v) +
         "-" + std::to_string(upper.v);
}

TEST(LineDetector, DefaultsAreTheLecture) {
  const LineDetectorConfig config;
  EXPECT_EQ(validate(config), "");
  EXPECT_EQ(config.lower.h, 20);
  EXPECT_EQ(config.lower.s, 100);
  EXPECT_EQ(config.lower.v, 40);  // not the lecture's 100: paint in a deep shadow reads V ~70
  EXPECT_EQ(config.upper.h, 40);  // not the lecture's 30: paint in a bluish shadow reads 32-38
  EXPECT_EQ(config.band.rows, 20);
  EXPECT_FALSE(config.look_ahead_enabled);
  // On the default mounting the bands land where the lecture's fractions put them: rows
  // [3/4 h, 3/4 h + 20) and [floor(0.55 h), that + 20) of 480.
  const BandPlacement band = placeBand(CameraGeometry(), config.band, 480);
  EXPECT_EQ(band.row_begin, 360);
  EXPECT_EQ(band.row_end, 380);
  EXPECT_FALSE(band.clamped);
  const BandPlacement look_ahead = placeBand(CameraGeometry(), config.look_ahead, 480);
  EXPECT_EQ(look_ahead.row_begin, 264);
  EXPECT_EQ(look_ahead.row_end, 284);
  EXPECT_FALSE(look_ahead.clamped);
}

// A camera with round numbers: fx = fy = 500, principal point (320, 240), 640 x 480.
CameraGeometry roundCamera(double height_m, double pitch_deg, double x_offset_m = 0.0) {
  CameraGeometry camera;
  camera.fx = camera.fy = 500.0;
  camera.cx = 320.0;
  camera.cy = 240.0;
  camera.height_m = height_m;
  camera.pitch_rad = pitch_deg * CV_PI / 180.0;
  camera.x_offset_m = x_offset_m;
  return camera;
}

TEST(GroundToRow, ExactRowsForKnownGeometry) {
  // Level, 0.5 m up: the floor 2.5 m ahead is 0.5 / 2.5 = 0.2 rad-tangent below the axis.
  EXPECT_NEAR(*groundToRow(roundCamera(0.5, 0.0), 2.5), 240.0 + 500.0 * 0.2, 1e-9);
  // 45 deg down, 1 m up: the optical axis meets the floor 1 m ahead of the optical centre, so
  // the floor there is on the principal row, wherever the camera sits on the base.
  EXPECT_NEAR(*groundToRow(roundCamera(1.0, 45.0), 1.0), 240.0, 1e-9);
  EXPECT_NEAR(*groundToRow(roundCamera(1.0, 45.0, 0.2), 1.2), 240.0, 1e-9);
  // 45 deg down, the floor right under the optical centre: 45 deg below the axis, tan = 1.
  EXPECT_NEAR(*groundToRow(roundCamera(1.0, 45.0), 0.0), 740.0, 1e-9);
  // Default camera, 0.46 m: cy + fy tan(atan(0.30 / 0.46) - 20 deg).
  const CameraGeometry standard;
  EXPECT_NEAR(*groundToRow(standard, 0.46),
              240.0 + 554.256 * std::tan(std::atan2(0.30, 0.46) - 20.0 * CV_PI / 180.0), 1e-9);
}

TEST(GroundToRow, InvertsPixelToGroundAtTheCentreColumn) {
  for (const double pitch_deg : {-10.0, 0.0, 10.0, 20.0, 30.0, 60.0}) {
    for (const double height_m : {0.2, 0.5}) {
      const CameraGeometry camera = roundCamera(height_m, pitch_deg, -0.087);
      for (int row = 0; row < 480; row += 7) {
        const std::optional<cv::Point2d> floor = pixelToGround(camera, camera.cx, row);
        if (!floor) continue;
        const std::optional<double> back = groundToRow(camera, floor->x);
        ASSERT_TRUE(back) << pitch_deg << " deg, row " << row;
        EXPECT_NEAR(*back, row, 1e-6) << pitch_deg << " deg, " << height_m << " m";
      }
    }
  }
}

TEST(GroundToRow, NothingForFloorNotInFrontOfTheCamera) {
  // Level camera 0.1 m ahead of base_link: the floor 5 cm ahead of the base is behind it.
  EXPECT_FALSE(groundToRow(roundCamera(0.3, 0.0, 0.1), 0.05));
  EXPECT_FALSE(groundToRow(roundCamera(0.3, 0.0), 0.0));  // under the lens: on the image plane
  EXPECT_FALSE(groundToRow(roundCamera(0.3, 0.0), std::nan("")));
}

// Expects `band` to be rows [row_begin, row_end), clamped or not, on the floor `distance_m` ahead
// (NaN: no floor in view).
void expectBand(const BandPlacement& band, int row_begin, int row_end, bool clamped,
                double distance_m) {
  EXPECT_EQ(band.row_begin, row_begin);
  EXPECT_EQ(band.row_end, row_end);
  EXPECT_EQ(band.clamped, clamped);
  if (std::isnan(distance_m)) {
    EXPECT_TRUE(std::isnan(band.distance_m));
  } else {
    EXPECT_NEAR(band.distance_m, distance_m, 1e-9);
  }
}

TEST(PlaceBand, CentresTheBandOnTheDistance) {
  // 0.5 m up, level: 2.5 m ahead is row 340, the centre of rows [330, 351).
  expectBand(placeBand(roundCamera(0.5, 0.0), BandConfig{2.5, 21}, 480), 330, 351, false, 2.5);
  // An even row count: the centre 340 - 9.5 rounds to row 331 (centre 340.5, 2.4876 m).
  const BandPlacement even = placeBand(roundCamera(0.5, 0.0), BandConfig{2.5, 20}, 480);
  EXPECT_EQ(even.row_begin, 331);
  EXPECT_NEAR(even.distance_m, 0.5 * 500.0 / 100.5, 1e-9);
}

TEST(PlaceBand, ClampsBelowTheHorizonWithMargin) {
  // Level, 0.3 m up: 10 m ahead is 15 rows below the horizon, inside the 2 deg margin
  // (500 tan 2 deg = 17.46 rows), so the band starts on row 258 and sees 0.3 * 500 / 27.5 m.
  expectBand(placeBand(roundCamera(0.3, 0.0), BandConfig{10.0, 20}, 480), 258, 278, true,
             0.3 * 500.0 / 27.5);
  // Pitched 10 deg down, the horizon is 500 tan 10 deg = 88.2 rows above the centre.
  const BandPlacement pitched = placeBand(roundCamera(0.3, 10.0), BandConfig{20.0, 20}, 480);
  EXPECT_TRUE(pitched.clamped);
  EXPECT_EQ(pitched.row_begin,
            static_cast<int>(std::ceil(240.0 - 500.0 * std::tan(8.0 * CV_PI / 180.0))));
}

TEST(PlaceBand, ClampsToTheBottomWhenTheFloorIsNearerThanTheCameraSees) {
  // Level, 0.2 m up: the nearest floor in view (row 479) is 0.2 * 500 / 239 = 0.42 m ahead.
  expectBand(placeBand(roundCamera(0.2, 0.0), BandConfig{0.3, 20}, 480), 460, 480, true,
             0.2 * 500.0 / 229.5);
  // Behind the camera: the bottom too.
  const BandPlacement behind = placeBand(roundCamera(0.3, 0.0, 0.1), BandConfig{0.05, 20}, 480);
  EXPECT_TRUE(behind.clamped);
  EXPECT_EQ(behind.row_begin, 460);
}

TEST(PlaceBand, BottomRowsWhenTheCameraSeesNoFloor) {
  // 30 deg up: the horizon is below the image.
  expectBand(placeBand(roundCamera(0.3, -30.0), BandConfig{0.46, 20}, 480), 460, 480, true,
             std::nan(""));
}

TEST(LineDetector, PlacesTheBandForItsCamera) {
  // Level, 0.5 m up: 2.5 m ahead is rows [330, 351).
  LineDetectorConfig config;
  config.band = {2.5, 21};
  cv::Mat frame = greyFrame();
  paintStripe(frame, 100, 10, 330, 351);
  paintStripe(frame, 500, 10, 360, 380);  // the default camera's band
  const LineMeasurement m = LineDetector(config, roundCamera(0.5, 0.0)).detect(frame);
  EXPECT_EQ(m.band.row_begin, 330);
  EXPECT_EQ(m.band.row_end, 351);
  EXPECT_FALSE(m.band.clamped);
  EXPECT_NEAR(m.band.centroid_x, 104.5, 1e-9);
}

TEST(LineDetector, FindsAStripeAtItsColumn) {
  cv::Mat frame = greyFrame();
  paintStripe(frame, 500, 11, 0, 480);  // columns 500..510
  const LineMeasurement m = LineDetector().detect(frame);
  ASSERT_TRUE(m.ok()) << m.error;
  EXPECT_EQ(m.image_width, 640);
  EXPECT_EQ(m.image_height, 480);
  EXPECT_TRUE(m.band.found);
  EXPECT_EQ(m.band.pixel_count, 11 * 20);
  EXPECT_NEAR(m.band.centroid_x, 505.0, 0.5);
  EXPECT_NEAR(m.band.centroid_y, 369.5, 0.5);
  EXPECT_NEAR(m.band.error_px, 185.0, 0.5);
  EXPECT_NEAR(m.band.error_normalised, 185.0 / 320.0, 1e-3);
  EXPECT_DOUBLE_EQ(m.band.confidence, 1.0);
  EXPECT_EQ(m.band.row_begin, 360);
  EXPECT_EQ(m.band.row_end, 380);
}

// The line at columns 300..310 and an off-line tape patch at 500..539, both through the band.
cv::Mat lineAndTapeFrame() {
  cv::Mat frame = greyFrame();
  paintStripe(frame, 300, 11, 0, 480);
  paintStripe(frame, 500, 40, 365, 480);  // tape: 40 columns, band rows 365..379
  return frame;
}

TEST(LineDetector, AsTheLectureWithoutAPreviousSightingTheTapePullsTheCentroid) {
  const BandMeasurement band = LineDetector(lectureConfig()).detect(lineAndTapeFrame()).band;
  EXPECT_EQ(band.pixel_count, 11 * 20 + 40 * 15);
  // (305 * 220 + 519.5 * 600) / 820
  EXPECT_DOUBLE_EQ(band.centroid_x, (305.0 * 220 + 519.5 * 600) / 820);
}

// Paint beside a larger patch of floor that a colour cast pushed into the colour box (HSV
// (25, 119, 150): in the default box, but far less saturated than paint), and a few such pixels
// at the image edge: only the paint is measured, whatever the sizes.
TEST(LineDetector, WithoutAPreviousSightingWeaklySaturatedBlobsAreLeftOut) {
  cv::Mat frame = greyFrame();
  paintStripe(frame, 300, 11, 0, 480);
  const cv::Scalar cast_floor(80, 138, 150);  // BGR
  frame(cv::Range(362, 380), cv::Range(420, 520)).setTo(cast_floor);
  frame(cv::Range(360, 380), cv::Range(637, 640)).setTo(cast_floor);
  cv::Mat hsv;
  cv::cvtColor(frame(cv::Rect(420, 370, 1, 1)), hsv, cv::COLOR_BGR2HSV);
  ASSERT_EQ(hsv.at<cv::Vec3b>(0, 0), cv::Vec3b(25, 119, 150));

  const BandMeasurement band = LineDetector().detect(frame).band;
  EXPECT_TRUE(band.found);
  EXPECT_EQ(band.pixel_count, 11 * 20);
  EXPECT_DOUBLE_EQ(band.centroid_x, 305.0);
  ASSERT_EQ(band.spans.size(), 20u);
  EXPECT_DOUBLE_EQ(band.spans.front().left, 299.5);
  EXPECT_DOUBLE_EQ(band.spans.front().right, 310.5);
  // The lecture's pipeline takes every pixel in the box: the cast floor pulls it far right.
  const BandMeasurement lecture = LineDetector(lectureConfig()).detect(frame).band;
  EXPECT_EQ(lecture.pixel_count, 11 * 20 + 100 * 18 + 3 * 20);
}

// A saturated speck below min_pixels does not set the bar: the paler line-sized blob stays.
TEST(LineDetector, ASaturatedSpeckBelowMinPixelsDoesNotSetTheBar) {
  cv::Mat frame = greyFrame();
  paintStripe(frame, 100, 4, 362, 368);  // 24 px of paint, fewer than min_pixels (30)
  const cv::Scalar paler_yellow(60, 180, 190);
  frame(cv::Range(0, 480), cv::Range(400, 411)).setTo(paler_yellow);
  const BandMeasurement band = LineDetector().detect(frame).band;
  EXPECT_EQ(band.pixel_count, 11 * 20 + 4 * 6);
  EXPECT_DOUBLE_EQ(band.centroid_x, (405.0 * 220 + 101.5 * 24) / 244);
}

TEST(LineDetector, KeepsTheBlobNearestThePreviousSighting) {
  const LineDetector detector;
  cv::Mat line_only = greyFrame();
  paintStripe(line_only, 300, 11, 0, 480);
  const LineMeasurement previous = detector.detect(line_only);
  ASSERT_TRUE(previous.band.found);

  const LineMeasurement m = detector.detect(lineAndTapeFrame(), previous);
  ASSERT_TRUE(m.ok()) << m.error;
  EXPECT_TRUE(m.band.found);
  EXPECT_EQ(m.band.pixel_count, 11 * 20);
  EXPECT_DOUBLE_EQ(m.band.centroid_x, 305.0);
  EXPECT_DOUBLE_EQ(m.band.centroid_y, 369.5);
  EXPECT_DOUBLE_EQ(m.band.error_px, -15.0);
  EXPECT_DOUBLE_EQ(m.band.confidence, 1.0);

  // A previous sighting on the tape's side keeps the tape instead: the hint decides.
  cv::Mat tape_side = greyFrame();
  paintStripe(tape_side, 520, 11, 0, 480);
  const BandMeasurement on_tape =
      detector.detect(lineAndTapeFrame(), detector.detect(tape_side)).band;
  EXPECT_EQ(on_tape.pixel_count, 40 * 15);
  EXPECT_DOUBLE_EQ(on_tape.centroid_x, 519.5);
  EXPECT_DOUBLE_EQ(on_tape.centroid_y, 372.0);
  EXPECT_DOUBLE_EQ(on_tape.confidence, 15.0 / 20.0);
}

TEST(LineDetector, APreviousSightingChangesNothingForASingleBlob) {
  const LineDetector detector;
  cv::Mat frame = greyFrame();
  paintStripe(frame, 300, 11, 0, 480);
  cv::Mat moved = greyFrame();
  paintStripe(moved, 200, 13, 0, 480);
  const BandMeasurement alone = detector.detect(moved).band;
  const BandMeasurement hinted = detector.detect(moved, detector.detect(frame)).band;
  EXPECT_EQ(hinted.pixel_count, alone.pixel_count);
  EXPECT_EQ(hinted.centroid_x, alone.centroid_x);
  EXPECT_EQ(hinted.centroid_y, alone.centroid_y);
  EXPECT_EQ(hinted.confidence, alone.confidence);
  // A hint from a frame of another size is ignored: all line pixels, as without one.
  const LineDetector lecture(lectureConfig());
  const BandMeasurement other_size =
      lecture.detect(lineAndTapeFrame(), lecture.detect(greyFrame(240, 320))).band;
  EXPECT_EQ(other_size.pixel_count, 11 * 20 + 40 * 15);
}

TEST(LineDetector, FindsAnAntiAliasedLineWithinHalfAPixel) {
  for (double x : {100.25, 319.5, 320.0, 421.75}) {
    cv::Mat frame = greyFrame();
    // Drawn with 4 fractional bits so the line's centre is at x exactly.
    const int fixed_x = cvRound(x * 16);
    cv::line(frame, cv::Point(fixed_x, 0), cv::Point(fixed_x, 479 * 16), kYellow, 9, cv::LINE_AA,
             4);
    const BandMeasurement band = LineDetector().detect(frame).band;
    ASSERT_TRUE(band.found);
    EXPECT_NEAR(band.centroid_x, x, 0.5) << x;
  }
}

// Where a curve enters or leaves the view the image's side edge cuts the line's patch: the
// band's centroid (the lecture's) lies off the line, its centre (whole runs only) on it.
TEST(LineDetector, MeasuresTheLineCentreFromRunsTheSideEdgesDoNotCut) {
  const LineDetector detector;
  // A patch cut by the left edge, below it a whole run.
  const BandMeasurement entering =
      detector.detect(stripedFrame({{0, 10, 360, 370}, {20, 10, 370, 380}})).band;
  EXPECT_EQ(entering.pixel_count, 200);
  EXPECT_DOUBLE_EQ(entering.centroid_x, 14.5);
  EXPECT_DOUBLE_EQ(entering.centroid_y, 369.5);
  EXPECT_EQ(entering.centre_pixel_count, 100);
  EXPECT_TRUE(entering.centre_found);
  EXPECT_DOUBLE_EQ(entering.centre_x, 24.5);
  EXPECT_DOUBLE_EQ(entering.centre_y, 374.5);
  ASSERT_EQ(entering.spans.size(), 10u);  // rows 370..379, the whole run's outer edges
  for (size_t i = 0; i < entering.spans.size(); ++i) {
    EXPECT_EQ(entering.spans[i].row, 370.0 + i);
    EXPECT_EQ(entering.spans[i].left, 19.5);
    EXPECT_EQ(entering.spans[i].right, 29.5);
  }

  // A patch cut by the right edge, below it a whole run.
  const BandMeasurement leaving =
      detector.detect(stripedFrame({{630, 10, 360, 365}, {600, 10, 365, 380}})).band;
  EXPECT_EQ(leaving.pixel_count, 200);
  EXPECT_EQ(leaving.centre_pixel_count, 150);
  EXPECT_DOUBLE_EQ(leaving.centre_x, 604.5);
  EXPECT_DOUBLE_EQ(leaving.centre_y, 372.0);
  ASSERT_EQ(leaving.spans.size(), 15u);
  EXPECT_EQ(leaving.spans.front().row, 365.0);
  EXPECT_EQ(leaving.spans.front().left, 599.5);
  EXPECT_EQ(leaving.spans.front().right, 609.5);

  // In one row a cut patch and a whole run: only the patch is left out.
  const BandMeasurement beside =
      detector.detect(stripedFrame({{0, 5, 360, 380}, {300, 11, 360, 380}, {620, 20, 360, 380}}))
          .band;
  EXPECT_EQ(beside.pixel_count, 36 * 20);
  EXPECT_DOUBLE_EQ(beside.centroid_x, (2.0 * 5 + 305.0 * 11 + 629.5 * 20) / 36);
  EXPECT_EQ(beside.centre_pixel_count, 11 * 20);
  EXPECT_DOUBLE_EQ(beside.centre_x, 305.0);
  EXPECT_DOUBLE_EQ(beside.centre_y, 369.5);
  ASSERT_EQ(beside.spans.size(), 20u);
  EXPECT_EQ(beside.spans.back().left, 299.5);
  EXPECT_EQ(beside.spans.back().right, 310.5);

  // A row entirely of line colour is cut at both edges.
  const BandMeasurement across =
      detector.detect(stripedFrame({{0, 640, 360, 361}, {300, 11, 361, 380}})).band;
  EXPECT_EQ(across.centre_pixel_count, 11 * 19);
  EXPECT_DOUBLE_EQ(across.centre_x, 305.0);
  EXPECT_DOUBLE_EQ(across.centre_y, 370.0);
  ASSERT_EQ(across.spans.size(), 19u);
  EXPECT_EQ(across.spans.front().row, 361.0);

  // Two whole runs in a row (a gap in the paint) and a cut one: the span is the whole runs'.
  const BandMeasurement gapped =
      detector.detect(stripedFrame({{300, 4, 360, 380}, {307, 4, 360, 380}, {630, 10, 360, 380}}))
          .band;
  ASSERT_EQ(gapped.spans.size(), 20u);
  EXPECT_EQ(gapped.spans[7].left, 299.5);
  EXPECT_EQ(gapped.spans[7].right, 310.5);
}

// Whole runs in fewer than 5 rows: the line crosses the band too obliquely for its centre.
TEST(LineDetector, TheCentreNeedsWholeRunsInFiveRows) {
  cv::Mat frame = greyFrame();
  paintStripe(frame, 0, 20, 360, 380);    // cut in every row
  paintStripe(frame, 100, 40, 375, 379);  // whole in rows 375..378
  const BandMeasurement four = LineDetector().detect(frame).band;
  EXPECT_EQ(four.centre_pixel_count, 160);
  EXPECT_EQ(four.spans.size(), 4u);
  EXPECT_FALSE(four.centre_found);
  paintStripe(frame, 100, 40, 374, 375);
  EXPECT_TRUE(LineDetector().detect(frame).band.centre_found);
  // A band of 3 rows needs them all.
  LineDetectorConfig short_band;
  short_band.band.rows = 3;
  short_band.min_pixels = 1;
  cv::Mat stripe = greyFrame();
  paintStripe(stripe, 300, 10, 0, 480);
  EXPECT_TRUE(LineDetector(short_band).detect(stripe).band.centre_found);
}

TEST(LineDetector, ALineCutInEveryRowIsFoundButHasNoCentre) {
  cv::Mat frame = greyFrame();
  paintStripe(frame, 0, 20, 0, 480);
  const BandMeasurement band = LineDetector().detect(frame).band;
  EXPECT_TRUE(band.found);
  EXPECT_DOUBLE_EQ(band.centroid_x, 9.5);
  EXPECT_EQ(band.centre_pixel_count, 0);
  EXPECT_FALSE(band.centre_found);

  // Whole runs below min_pixels (30): a centre, not found.
  paintStripe(frame, 300, 10, 360, 362);
  const BandMeasurement few = LineDetector().detect(frame).band;
  EXPECT_EQ(few.centre_pixel_count, 20);
  EXPECT_FALSE(few.centre_found);
  EXPECT_DOUBLE_EQ(few.centre_x, 304.5);
  EXPECT_DOUBLE_EQ(few.centre_y, 360.5);
}

// A 9 px anti-aliased line at 45 deg leaving through the left edge: x = 374 - y.
TEST(LineDetector, TheCentreOfAnObliqueLineCutByTheEdgeLiesOnIt) {
  cv::Mat frame = greyFrame();
  cv::line(frame, cv::Point(374 - 300, 300), cv::Point(374 - 420, 420), kYellow, 9, cv::LINE_AA);
  const BandMeasurement band = LineDetector().detect(frame).band;
  ASSERT_TRUE(band.centre_found);
  EXPECT_NEAR(band.centre_x, 374.0 - band.centre_y, 0.5);
  EXPECT_GT(band.centroid_x - (374.0 - band.centroid_y), 1.4);  // the cut rows pull it right
}

TEST(LineDetector, TheNearestBlobsCentreLeavesOutItsCutRuns) {
  const LineDetector detector;
  cv::Mat frame = greyFrame();
  paintStripe(frame, 300, 11, 0, 480);
  paintStripe(frame, 600, 40, 365, 480);  // tape cut by the right edge, band rows 365..379
  cv::Mat line_only = greyFrame();
  paintStripe(line_only, 300, 11, 0, 480);
  const BandMeasurement on_line = detector.detect(frame, detector.detect(line_only)).band;
  EXPECT_EQ(on_line.pixel_count, 11 * 20);
  EXPECT_EQ(on_line.centre_pixel_count, 11 * 20);
  EXPECT_DOUBLE_EQ(on_line.centre_x, 305.0);
  // Kept for the hint, the tape is cut in every row: found, no centre.
  cv::Mat tape_side = greyFrame();
  paintStripe(tape_side, 610, 11, 0, 480);
  const BandMeasurement on_tape = detector.detect(frame, detector.detect(tape_side)).band;
  EXPECT_EQ(on_tape.pixel_count, 40 * 15);
  EXPECT_EQ(on_tape.centre_pixel_count, 0);
  EXPECT_FALSE(on_tape.centre_found);
}

// The spans of a `half_width` line along the circle of `radius` about `centre` (floor, m) in
// rows [row_begin, row_end) of `camera`: where each row's floor line meets the circles
// radius +- half_width, the crossing nearest `near`, in exact (fractional) columns.
std::vector<BandMeasurement::RowSpan> curveSpans(const CameraGeometry& camera, int row_begin,
                                                 int row_end, const cv::Point2d& centre,
                                                 double radius, double half_width,
                                                 const cv::Point2d& near) {
  std::vector<BandMeasurement::RowSpan> spans;
  for (int row = row_begin; row < row_end; ++row) {
    const cv::Point2d a = *pixelToGround(camera, camera.cx - 100.0, row);
    const cv::Point2d along = *pixelToGround(camera, camera.cx + 100.0, row) - a;
    double columns[2];
    for (int side = 0; side < 2; ++side) {
      const double r = radius + (side == 0 ? -half_width : half_width);
      // |a + t along - centre| = r, the root nearest `near`.
      const cv::Point2d d = a - centre;
      const double qa = along.dot(along), qb = 2.0 * along.dot(d), qc = d.dot(d) - r * r;
      const double root = std::sqrt(qb * qb - 4.0 * qa * qc);
      const cv::Point2d first = a + (-qb - root) / (2.0 * qa) * along;
      const cv::Point2d second = a + (-qb + root) / (2.0 * qa) * along;
      const cv::Point2d& hit = cv::norm(first - near) < cv::norm(second - near) ? first : second;
      columns[side] = projectToPixel(camera, hit).x;
    }
    spans.push_back({static_cast<double>(row), std::min(columns[0], columns[1]),
                     std::max(columns[0], columns[1])});
  }
  return spans;
}

// The 0.5 m level camera's band (the image's bottom 20 rows, ~1.2 m ahead) across a 5 cm line
// on 1 m and 0.6 m curves, crossing its rows at up to 55 deg from square: the centre lies on the
// line's centre, where the spans' middles (and so the band's centroid) lie mm inside the curve.
TEST(FloorCentre, PlacesTheCentreOfACurvedLineOnIt) {
  CameraGeometry camera = harnessCamera();
  camera.height_m = 0.5;
  camera.pitch_rad = 0.0;
  const cv::Point2d crossing = *pixelToGround(camera, camera.cx, 469.5);
  for (double radius : {1.0, -1.0, 0.6}) {  // negative: the centre to the right
    for (double heading_deg : {0.0, 30.0, 55.0}) {
      const double heading = degrees(heading_deg);
      const cv::Point2d centre =
          crossing + radius * cv::Point2d(-std::sin(heading), std::cos(heading));
      BandMeasurement band;
      band.spans = curveSpans(camera, 460, 480, centre, std::abs(radius), 0.025, crossing);
      const std::optional<cv::Point2d> found = floorCentre(band, camera);
      ASSERT_TRUE(found);
      const double off_line = cv::norm(*found - centre) - std::abs(radius);
      EXPECT_LT(std::abs(off_line), 1e-4) << radius << " m, " << heading_deg << " deg";
      // The spans' middles, on the floor, and their mean.
      cv::Point2d middles(0.0, 0.0);
      for (const BandMeasurement::RowSpan& span : band.spans) {
        middles += *pixelToGround(camera, 0.5 * (span.left + span.right), span.row);
      }
      middles *= 1.0 / band.spans.size();
      const double middles_inside = std::abs(radius) - cv::norm(middles - centre);
      if (heading_deg == 55.0) EXPECT_GT(middles_inside, 2e-3) << radius << " m";
    }
  }
  // A straight line across the band: its centre exactly.
  BandMeasurement straight;
  for (int row = 460; row < 480; ++row) straight.spans.push_back({row * 1.0, 300.0, 340.0});
  const std::optional<cv::Point2d> ahead = floorCentre(straight, camera);
  ASSERT_TRUE(ahead);
  EXPECT_NEAR(ahead->y, 0.0, 1e-12);
  // One row: its span's middle; none: nothing.
  BandMeasurement one;
  one.spans = {{470.0, 300.0, 340.0}};
  EXPECT_NEAR(floorCentre(one, camera)->y, pixelToGround(camera, 320.0, 470.0)->y, 1e-12);
  EXPECT_FALSE(floorCentre(BandMeasurement(), camera));
  // A span above the horizon does not meet the floor.
  one.spans.push_back({100.0, 300.0, 340.0});
  EXPECT_FALSE(floorCentre(one, camera));
}

TEST(LineDetector, IgnoresLineColourOutsideTheBand) {
  cv::Mat frame = greyFrame();
  paintStripe(frame, 0, 640, 0, 360);    // everything above the band, up to row 359
  paintStripe(frame, 0, 640, 380, 480);  // everything below, from row 380
  paintStripe(frame, 100, 10, 360, 380);
  const BandMeasurement band = LineDetector().detect(frame).band;
  EXPECT_EQ(band.pixel_count, 200);
  EXPECT_NEAR(band.centroid_x, 104.5, 1e-9);
  EXPECT_NEAR(band.centroid_y, 369.5, 1e-9);
}

TEST(LineDetector, ReportsNothingWithoutLineColour) {
  cv::Mat frame = greyFrame();
  cv::RNG rng(3);
  cv::Mat noise(frame.size(), CV_8UC3);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 40);
  frame += noise;
  const LineMeasurement m = LineDetector().detect(frame);
  ASSERT_TRUE(m.ok());
  EXPECT_FALSE(m.band.found);
  EXPECT_EQ(m.band.pixel_count, 0);
  EXPECT_EQ(m.band.confidence, 0.0);
  EXPECT_EQ(m.band.error_normalised, 0.0);
}

TEST(LineDetector, AnAllYellowFrameIsNoLineOrAsTheLectureFoundWithZeroConfidence) {
  cv::Mat frame(480, 640, CV_8UC3, kYellow);
  // The floor test: nothing is yellower than the band's own floor.
  EXPECT_EQ(LineDetector().detect(frame).band.pixel_count, 0);
  const BandMeasurement band = LineDetector(lectureConfig()).detect(frame).band;
  EXPECT_TRUE(band.found);
  EXPECT_EQ(band.pixel_count, 640 * 20);
  EXPECT_NEAR(band.error_px, -0.5, 1e-9);  // pixel-index centroid 319.5
  EXPECT_EQ(band.confidence, 0.0);
}

TEST(LineDetector, ConfidenceFallsForShortAndWideLines) {
  LineDetector detector;
  cv::Mat ends_in_band = greyFrame();
  paintStripe(ends_in_band, 300, 20, 375, 480);  // only the band's last 5 rows
  EXPECT_DOUBLE_EQ(detector.detect(ends_in_band).band.confidence, 0.25);

  cv::Mat wide = greyFrame();
  paintStripe(wide, 0, 416, 0, 480);  // 65% of the width
  // Width sanity (1 - 0.65) / (1 - 0.35) with the default max_width_fraction, as the lecture
  // (the floor test and the width gate leave nothing of it).
  EXPECT_NEAR(LineDetector(lectureConfig()).detect(wide).band.confidence, 0.35 / 0.65, 1e-9);
  EXPECT_EQ(detector.detect(wide).band.pixel_count, 0);
}

TEST(LineDetector, FewPixelsGiveACentroidButNotFound) {
  cv::Mat frame = greyFrame();
  paintStripe(frame, 200, 1, 360, 365);  // 5 pixels, below min_pixels = 30
  const BandMeasurement band = LineDetector().detect(frame).band;
  EXPECT_FALSE(band.found);
  EXPECT_EQ(band.pixel_count, 5);
  EXPECT_DOUBLE_EQ(band.centroid_x, 200.0);
  EXPECT_DOUBLE_EQ(band.centroid_y, 362.0);
}

TEST(LineDetector, ClipsTheBandToSmallFrames) {
  LineDetector detector(lectureConfig());  // a frame of nothing but yellow
  cv::Mat tiny(10, 12, CV_8UC3, kYellow);  // shorter than the band: all its rows
  BandMeasurement band = detector.detect(tiny).band;
  EXPECT_EQ(band.row_begin, 0);
  EXPECT_EQ(band.row_end, 10);
  EXPECT_TRUE(band.clamped);
  EXPECT_EQ(band.pixel_count, 120);
  EXPECT_TRUE(band.found);
  EXPECT_DOUBLE_EQ(band.centroid_y, 4.5);

  cv::Mat one_pixel(1, 1, CV_8UC3, kYellow);
  band = detector.detect(one_pixel).band;
  EXPECT_EQ(band.row_begin, 0);
  EXPECT_EQ(band.row_end, 1);
  EXPECT_EQ(band.pixel_count, 1);
  EXPECT_FALSE(band.found);
}

TEST(LineDetector, RejectsEmptyAndNonBgr8FramesWithoutThrowing) {
  LineDetector detector;
  LineMeasurement m;
  EXPECT_NO_THROW(m = detector.detect(cv::Mat()));
  EXPECT_FALSE(m.ok());
  EXPECT_EQ(m.error, "empty image");
  EXPECT_FALSE(m.band.found);

  for (int type : {CV_8UC1, CV_8UC4, CV_16UC3, CV_32FC3, CV_8SC3}) {
    const cv::Mat frame(48, 64, type, cv::Scalar::all(200));
    EXPECT_NO_THROW(m = detector.detect(frame));
    EXPECT_FALSE(m.ok()) << type;
    EXPECT_NE(m.error.find("CV_8UC3"), std::string::npos) << m.error;
    EXPECT_FALSE(m.band.found);
    EXPECT_TRUE(detector.debugMask(frame).empty());
  }
}

TEST(LineDetector, ReadsRegionsOfInterestWithTheirStride) {
  cv::Mat big = greyFrame(600, 800);
  paintStripe(big, 150 + 400, 10, 0, 600);  // column 400 of the ROI below
  const cv::Mat roi = big(cv::Rect(150, 60, 640, 480));
  ASSERT_FALSE(roi.isContinuous());
  const BandMeasurement band = LineDetector().detect(roi).band;
  EXPECT_EQ(band.pixel_count, 200);
  EXPECT_NEAR(band.centroid_x, 404.5, 1e-9);
}

TEST(LineDetector, MeasuresTheLookAheadBandWhenEnabled) {
  LineDetectorConfig config;
  config.look_ahead_enabled = true;
  // Rows [240, 250): centred on row 244.5 of the default camera.
  config.look_ahead = {pixelToGround(CameraGeometry(), 320.0, 244.5)->x, 10};
  cv::Mat frame = greyFrame();
  paintStripe(frame, 400, 10, 240, 250);
  paintStripe(frame, 300, 10, 360, 380);
  const LineMeasurement m = LineDetector(config).detect(frame);
  EXPECT_NEAR(m.band.centroid_x, 304.5, 1e-9);
  EXPECT_TRUE(m.look_ahead.found);
  EXPECT_EQ(m.look_ahead.row_begin, 240);
  EXPECT_EQ(m.look_ahead.row_end, 250);
  EXPECT_NEAR(m.look_ahead.centroid_x, 404.5, 1e-9);
  EXPECT_NEAR(m.look_ahead.centroid_y, 244.5, 1e-9);

  const LineMeasurement without = LineDetector().detect(frame);
  EXPECT_FALSE(without.look_ahead.found);
  EXPECT_EQ(without.look_ahead.pixel_count, 0);
}

// Yellow paint under an even light, on the grey floor, as a camera sees them (sensor noise
// sigma 4): HSV (27, 221, 225), yellowness 175, the bench's line colour.
const cv::Scalar kPaint(30, 205, 225);
constexpr double kSensorNoise = 4.0;

// A straight line ahead through the whole frame, `width` columns from `x`, on the grey floor.
cv::Mat paintedFloor(int x, int width) {
  cv::Mat frame = greyFrame();
  frame(cv::Range::all(), cv::Range(x, x + width)).setTo(kPaint);
  return frame;
}

// Light falling on `region` at `brightness` of the rest, per channel times `tint` (BGR): a
// shadow lit by the sky is bluish, a lamp warm.
void relight(cv::Mat& frame, const cv::Rect& region, double brightness, const cv::Scalar& tint) {
  cv::Mat part = frame(region);
  std::vector<cv::Mat> channels;
  cv::split(part, channels);
  for (int c = 0; c < 3; ++c) channels[c].convertTo(channels[c], -1, brightness * tint[c]);
  cv::merge(channels, part);
}

void addSensorNoise(cv::Mat& frame, int seed, double sigma = kSensorNoise) {
  cv::Mat noisy;
  frame.convertTo(noisy, CV_32FC3);
  cv::Mat noise(frame.size(), CV_32FC3);
  cv::RNG(seed).fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  noisy += noise;
  noisy.convertTo(frame, CV_8UC3);
}

const cv::Scalar kSkyShadowTint(1.1, 1.0, 0.95);  // BGR: blue up, red down

TEST(LineDetector, FitsTheFloorTestToTheBandsFloor) {
  // Grey floor: yellowness min(120, 115) - 110 = 5 everywhere, so 5 + floor_margin (40).
  EXPECT_EQ(LineDetector().detect(greyFrame()).band.min_yellowness, 45);
  // A warm cast: the floor's yellowness 58, the threshold with it.
  cv::Mat cast(480, 640, CV_8UC3, cv::Scalar(80, 138, 150));
  EXPECT_EQ(LineDetector().detect(cast).band.min_yellowness, 98);
  // A noisy cast floor (sigma 16): there the margin in MADs is the larger, and the tail of the
  // floor's noise stays out.
  addSensorNoise(cast, 9, 16.0);
  LineDetectorConfig margin_only;
  margin_only.floor_mads = 0.0;
  const BandMeasurement band = LineDetector().detect(cast).band;
  const BandMeasurement by_margin = LineDetector(margin_only).detect(cast).band;
  EXPECT_GT(band.min_yellowness, by_margin.min_yellowness);
  EXPECT_FALSE(band.found);
  // Counted in the floor test's mask, before the blob rules pick among the specks.
  EXPECT_GT(cv::countNonZero(LineDetector(margin_only).debugMask(cast)),
            3 * cv::countNonZero(LineDetector().debugMask(cast)));
  EXPECT_EQ(LineDetector(lectureConfig()).detect(cast).band.min_yellowness, 0);
}

// The line in a hard shadow at 30 % and 55 % of the lit floor's light, bluish (sky-lit): its V
// (~65 at 30 %) is far below the lecture's V floor of 100, but it is far yellower than the
// shadowed floor round it. The shadow covers the whole band, or only its left part (the line
// and 400 columns), where the band's floor median is of both lights.
TEST(LineDetector, FindsTheLineInAHardShadow) {
  const int line_x = 250, width = 50;  // 5 cm at the band's 0.97 mm per column
  const double centre = line_x + (width - 1) / 2.0;
  for (double brightness : {0.3, 0.55}) {
    for (int shadow_columns : {640, 400}) {
      cv::Mat frame = paintedFloor(line_x, width);
      relight(frame, cv::Rect(0, 0, shadow_columns, 480), brightness, kSkyShadowTint);
      addSensorNoise(frame, 1);
      const BandMeasurement band = LineDetector().detect(frame).band;
      const std::string where =
          std::to_string(brightness) + " over " + std::to_string(shadow_columns) + " columns";
      EXPECT_TRUE(band.found) << where;
      EXPECT_NEAR(band.centroid_x, centre, 1.0) << where;
      // Where noise tips the dim paint's hue out of the box some pixels are lost.
      EXPECT_GE(band.pixel_count, 20 * width / 2) << where;
      if (brightness == 0.3) {
        EXPECT_FALSE(LineDetector(lectureConfig()).detect(frame).band.found) << where;
      }
    }
  }
}

// The whole frame at 22 % of the light: the paint's yellowness (~38) is below the floor test's
// full margin over the floor (0 + 40), but every yellowness in the band is dimmer, and the margin
// dims with the band's brightest pixels (~47 of 120: a quarter of it, 10). The grey floor and a
// warm cast floor in the same light (yellowness ~15, at the colour box's S floor) are no line.
TEST(LineDetector, FindsTheLineWhenTheWholeBandIsDimmerThanTheMargin) {
  const int line_x = 250, width = 50;
  cv::Mat frame = paintedFloor(line_x, width);
  relight(frame, cv::Rect(0, 0, 640, 480), 0.22, kSkyShadowTint);
  addSensorNoise(frame, 4);
  const BandMeasurement band = LineDetector().detect(frame).band;
  EXPECT_TRUE(band.found);
  EXPECT_NEAR(band.centroid_x, line_x + (width - 1) / 2.0, 1.0);
  EXPECT_GE(band.pixel_count, 20 * width / 2);
  EXPECT_LT(band.min_yellowness, 25);
  for (const cv::Scalar& floor_colour : {kGrey, cv::Scalar(80, 138, 150)}) {
    for (double brightness : {0.22, 0.3}) {
      cv::Mat floor(480, 640, CV_8UC3, floor_colour);
      relight(floor, cv::Rect(0, 0, 640, 480), brightness, kSkyShadowTint);
      addSensorNoise(floor, 5);
      EXPECT_FALSE(LineDetector().detect(floor).band.found) << floor_colour << " " << brightness;
    }
  }
}

// A shadow over the line and little else, on a lit warm floor near the paint's hue (wood: HSV
// (13, 153, 150), yellowness 40): the band's floor is mostly lit, so its median yellowness is
// the lit wood's and the paint in the shadow (34 % of the light, tinted as by a clear sky:
// yellowness ~52) is under the band's threshold (~80). Each column block judged in its own
// light (its threshold scaled by the block's light over the band's, at most halved: ~40), the
// line is found; the wood in the same shadow (yellowness ~8) is not.
TEST(LineDetector, FindsTheLineInAShadowOverItAlone) {
  const cv::Scalar wood(60, 100, 150);
  const cv::Scalar clear_sky_tint(1.3, 1.0, 0.85);
  const int line_x = 250, width = 50;
  const double centre = line_x + (width - 1) / 2.0;
  const cv::Rect shadow(line_x - 60, 0, width + 120, 480);  // columns 190-359: blocks 1 and 2
  cv::Mat frame(480, 640, CV_8UC3, wood);
  frame(cv::Range::all(), cv::Range(line_x, line_x + width)).setTo(kPaint);
  relight(frame, shadow, 0.34, clear_sky_tint);
  addSensorNoise(frame, 4);
  const BandMeasurement band = LineDetector().detect(frame).band;
  EXPECT_GE(band.min_yellowness, 52 + 20);  // far above the shadowed paint's yellowness
  ASSERT_EQ(band.block_min_yellowness.size(), 5u);
  for (int block : {0, 3, 4}) EXPECT_EQ(band.block_min_yellowness[block], band.min_yellowness);
  for (int block : {1, 2}) {
    EXPECT_EQ(band.block_min_yellowness[block], (band.min_yellowness + 1) / 2) << block;
  }
  EXPECT_TRUE(band.found);
  EXPECT_NEAR(band.centroid_x, centre, 1.0);
  EXPECT_GE(band.pixel_count, 20 * width / 2);  // noise tips some dim paint under the margin
  // The wood alone, lit and in the same shadow, is no line.
  cv::Mat bare(480, 640, CV_8UC3, wood);
  relight(bare, shadow, 0.34, clear_sky_tint);
  addSensorNoise(bare, 5);
  EXPECT_EQ(LineDetector().detect(bare).band.pixel_count, 0);
}

// A `wood` floor with the line `width` columns from `line_x`, `shadow` relit to `brightness` under
// the sky's tint, and sensor noise of draw `seed`.
cv::Mat woodWithLineInShadow(const cv::Scalar& wood, int line_x, int width, const cv::Rect& shadow,
                             double brightness, int seed) {
  cv::Mat frame(480, 640, CV_8UC3, wood);
  frame(cv::Range::all(), cv::Range(line_x, line_x + width)).setTo(kPaint);
  relight(frame, shadow, brightness, kSkyShadowTint);
  addSensorNoise(frame, seed);
  return frame;
}

// The line found on its centre, from at least half of its pixels (noise tips some dim paint under
// the margin).
void expectDimLineFound(const BandMeasurement& band, int line_x, int width) {
  EXPECT_TRUE(band.found);
  EXPECT_NEAR(band.centroid_x, line_x + (width - 1) / 2.0, 1.0);
  EXPECT_GE(band.pixel_count, 20 * width / 2);
}

// A hard shadow (half the light, sky-tinted) whose edge runs along the line's right side, the
// line in it (yellowness ~86), lit wood floor beyond (HSV (13, 150, 210), yellowness 84): the
// shadow covers three quarters of the band (columns 0-479), so the band's light and median
// yellowness are the shadow's, whose threshold (~80) the lit wood clears. Joined to the line, it
// made one blob too wide to be the line, and the line was lost. A lit block whose floor is the
// band's floor in more light sets the test for every pixel about as bright as it: its own floor's
// threshold, so the lit wood stays out.
TEST(LineDetector, KeepsTheLitFloorBesideAShadowOut) {
  const int line_x = 430, width = 50, edge = line_x + width;
  const double centre = line_x + (width - 1) / 2.0;
  const cv::Mat frame = woodWithLineInShadow(cv::Scalar(87, 171, 210), line_x, width,
                                             cv::Rect(0, 0, edge, 480), 0.5, 6);
  const LineDetector detector;
  const BandMeasurement band = detector.detect(frame).band;
  expectDimLineFound(band, line_x, width);
  const cv::Mat mask = detector.debugMask(frame);
  EXPECT_EQ(cv::countNonZero(mask(cv::Range::all(), cv::Range(edge, 640))), 0);
  // Tracking from a sighting on the line, the same.
  LineMeasurement previous;
  previous.image_width = 640;
  previous.image_height = 480;
  previous.band = band;
  EXPECT_NEAR(detector.detect(frame, previous).band.centroid_x, centre, 1.0);
}

// A hard shadow over the band's right half, the line in it (sweep member 113): the lit wood
// reads as yellow as the shadowed paint (~55 against ~60). Its floor and the shadow's made the
// band's yellowness two modes, whose median fell between them and whose MAD raised the threshold
// far above the paint: the line was lost for 1.5 s. Each block's samples are taken
// to the band's light before the median and MAD, and the floor is one mode again.
TEST(LineDetector, FindsThePaintInAShadowBesideLitWoodAsYellow) {
  const int shadow_x = 300, line_x = 560, width = 50;
  const cv::Mat frame = woodWithLineInShadow(cv::Scalar(45, 100, 125), line_x, width,
                                             cv::Rect(shadow_x, 0, 640 - shadow_x, 480), 0.35, 8);
  const LineDetector detector;
  expectDimLineFound(detector.detect(frame).band, line_x, width);
  const cv::Mat mask = detector.debugMask(frame);
  EXPECT_EQ(cv::countNonZero(mask(cv::Range::all(), cv::Range(0, line_x))), 0);
}

// Without a previous sighting, blobs are compared by saturation, which a shadow leaves alone:
// the line in a shadow over it alone (yellowness ~52, chroma ~57, S ~0.8) and, in the light,
// a line-sized patch of cardboard (HSV (24, 150, 170), chroma 100, S 0.59) that clears the lit
// grey floor's test. By chroma the cardboard would be the stronger blob and the paint left out.
TEST(LineDetector, PrefersThePaintInAShadowToALitDullerPatch) {
  const cv::Scalar clear_sky_tint(1.3, 1.0, 0.85);
  const int line_x = 250, width = 50, patch_x = 500;
  const double centre = line_x + (width - 1) / 2.0;
  cv::Mat frame = paintedFloor(line_x, width);
  frame(cv::Range::all(), cv::Range(patch_x, patch_x + width)).setTo(cv::Scalar(70, 150, 170));
  relight(frame, cv::Rect(line_x - 60, 0, width + 120, 480), 0.34, clear_sky_tint);
  addSensorNoise(frame, 7);
  const BandMeasurement band = LineDetector().detect(frame).band;
  EXPECT_TRUE(band.found);
  EXPECT_NEAR(band.centroid_x, centre, 1.0);
  // Both blobs pass the floor test: the choice is the blob rule's.
  const cv::Mat mask = LineDetector().debugMask(frame);
  EXPECT_GT(cv::countNonZero(mask(cv::Range::all(), cv::Range(patch_x, patch_x + width))),
            20 * width / 2);
}

// Bare floor is no line whatever the light does to it: under a warm cast that puts the whole
// floor in the colour box; a glare patch on a dark warm floor, in the box where the floor is not;
// the edge of a hard shadow on the cast floor, its lit side in the box. The lecture's pipeline
// reports a line in each. The shadow edge's lit side is 43 levels yellower than the shadowed
// side, over floor_margin; the lit block's own floor test keeps every pixel of it out, in every
// noise draw (before that rule, about half passed, and 2 draws of 25 left a piece narrower than
// the width gate).
TEST(LineDetector, BareFloorUnderACastGlareOrAShadowEdgeIsNoLine) {
  cv::Mat cast(480, 640, CV_8UC3, cv::Scalar(80, 138, 150));  // HSV (25, 119, 150)
  cv::Mat glare(480, 640, CV_8UC3, cv::Scalar(45, 85, 95));   // HSV (24, 134, 95)
  cv::ellipse(glare, cv::Point(420, 370), cv::Size(90, 40), 0.0, 0.0, 360.0,
              cv::Scalar(95, 150, 165), cv::FILLED, cv::LINE_AA);  // HSV (26, 108, 165)
  cv::Mat shadow_edge = cast.clone();
  relight(shadow_edge, cv::Rect(0, 0, 420, 480), 0.3, kSkyShadowTint);
  const std::vector<std::pair<std::string, cv::Mat>> floors = {
      {"cast", cast}, {"glare", glare}, {"shadow edge", shadow_edge}};
  for (auto [name, frame] : floors) {
    addSensorNoise(frame, 2);
    EXPECT_FALSE(LineDetector().detect(frame).band.found) << name;
    EXPECT_TRUE(LineDetector(lectureConfig()).detect(frame).band.found) << name;
  }
  for (int seed = 10; seed < 35; ++seed) {
    cv::Mat noisy(480, 640, CV_8UC3, cv::Scalar(80, 138, 150));
    relight(noisy, cv::Rect(0, 0, 420, 480), 0.3, kSkyShadowTint);
    addSensorNoise(noisy, seed);
    EXPECT_EQ(cv::countNonZero(LineDetector().debugMask(noisy)), 0) << seed;
  }
}

// The far band sees a line-yellow box 20 cm wide beside the line: as wide as four lines on the
// floor, it is not the line, so the sighting stays on the line with or without a previous one;
// the lecture's centroid goes 200 px towards the box.
TEST(LineDetector, AYellowObjectWiderThanTheLineIsNotTheLine) {
  LineDetectorConfig config;
  config.look_ahead_enabled = true;
  const int line_x = 200, width = 40;  // 5.4 cm at the look-ahead band's 1.35 mm per column
  cv::Mat frame = paintedFloor(line_x, width);
  const BandPlacement far_band = placeBand(CameraGeometry(), config.look_ahead, 480);
  frame(cv::Range(far_band.row_begin - 30, far_band.row_end + 10), cv::Range(420, 570))
      .setTo(kPaint);  // 150 columns: 20 cm
  addSensorNoise(frame, 3);
  const double centre = line_x + (width - 1) / 2.0;
  const LineDetector detector(config);
  const LineMeasurement m = detector.detect(frame);
  EXPECT_TRUE(m.look_ahead.found);
  EXPECT_NEAR(m.look_ahead.centroid_x, centre, 1.0);
  EXPECT_NEAR(m.band.centroid_x, centre, 1.0);
  EXPECT_NEAR(detector.detect(frame, m).look_ahead.centroid_x, centre, 1.0);
  LineDetectorConfig lecture = lectureConfig();
  lecture.look_ahead_enabled = true;
  EXPECT_GT(LineDetector(lecture).detect(frame).look_ahead.centroid_x, centre + 150.0);
  // The box alone is no line either.
  cv::Mat box_only = greyFrame();
  box_only(cv::Range(far_band.row_begin - 30, far_band.row_end + 10), cv::Range(420, 570))
      .setTo(kPaint);
  EXPECT_FALSE(detector.detect(box_only).look_ahead.found);
}

// The width is measured across the line's direction on the floor: a line crossing the band
// obliquely has long runs but is still the line; the same runs on a blob square to the rows are
// too wide.
TEST(LineDetector, MeasuresTheWidthAcrossTheLinesDirection) {
  // A 5 cm line at 70 deg to the heading, through the band's centre 0.46 m ahead: on the floor,
  // x = 0.46 + t cos 70, y = -t sin 70; drawn by projecting its edges' ends.
  const CameraGeometry camera;
  const double angle = 70.0 * CV_PI / 180.0, half_width = 0.025;
  std::vector<cv::Point> corners;
  for (double side : {-1.0, 1.0}) {
    for (double t :
         side < 0 ? std::vector<double>{-0.08, 0.08} : std::vector<double>{0.08, -0.08}) {
      const double x = 0.46 + t * std::cos(angle) + side * half_width * std::sin(angle);
      const double y = -t * std::sin(angle) + side * half_width * std::cos(angle);
      // Floor to pixel: the ray through (x, y, -height) in the optical frame.
      const double ahead = x - camera.x_offset_m;
      const double depth =
          ahead * std::cos(camera.pitch_rad) + camera.height_m * std::sin(camera.pitch_rad);
      const double down =
          camera.height_m * std::cos(camera.pitch_rad) - ahead * std::sin(camera.pitch_rad);
      corners.emplace_back(cvRound(camera.cx - camera.fx * y / depth),
                           cvRound(camera.cy + camera.fy * down / depth));
    }
  }
  cv::Mat frame = greyFrame();
  cv::fillConvexPoly(frame, corners, kPaint);
  const BandMeasurement band = LineDetector().detect(frame).band;
  ASSERT_TRUE(band.found);
  const double mean_run = static_cast<double>(band.pixel_count) / 20.0;
  EXPECT_GT(mean_run, 2.5 * 0.05 / 0.00097);  // as long as a blob too wide to be the line
  // A blob square to the rows with runs that long is too wide.
  EXPECT_FALSE(LineDetector().detect(paintedFloor(200, cvRound(mean_run))).band.found);
}

// Every one of the 2^24 colours, through the detector's vectorised path, against
// cv::cvtColor + cv::inRange.
TEST(LineDetector, MatchesCvtColorAndInRangeOnEveryColour) {
  cv::Mat all_colours(4096, 4096, CV_8UC3);
  for (int i = 0; i < (1 << 24); ++i) {
    all_colours.at<cv::Vec3b>(i >> 12, i & 4095) =
        cv::Vec3b(i & 255, (i >> 8) & 255, (i >> 16) & 255);
  }
  cv::Mat hsv;
  cv::cvtColor(all_colours, hsv, cv::COLOR_BGR2HSV);
  // A camera pitched 60 deg down: its horizon is far above the frame, so a band of 4096 rows
  // covers the whole frame.
  CameraGeometry steep;
  steep.pitch_rad = 60.0 * M_PI / 180.0;
  for (const auto& [lower, upper] : boundSets()) {
    LineDetectorConfig config = withBounds(lower, upper);
    config.band = {1.0, 4096};
    cv::Mat expected;
    cv::inRange(hsv, cv::Scalar(lower.h, lower.s, lower.v), cv::Scalar(upper.h, upper.s, upper.v),
                expected);
    const cv::Mat mask = LineDetector(config, steep).debugMask(all_colours);
    EXPECT_EQ(cv::countNonZero(mask != expected), 0) << describe(lower, upper);
  }
}

// The same through HsvBox::contains, the scalar path, on random pixels.
TEST(HsvBox, MatchesCvtColorAndInRangeOnRandomPixels) {
  cv::Mat pixels(1, 200000, CV_8UC3);
  cv::RNG(11).fill(pixels, cv::RNG::UNIFORM, 0, 256);
  cv::Mat hsv;
  cv::cvtColor(pixels, hsv, cv::COLOR_BGR2HSV);
  for (const auto& [lower, upper] : boundSets()) {
    const HsvBox box(lower, upper);
    cv::Mat expected;
    cv::inRange(hsv, cv::Scalar(lower.h, lower.s, lower.v), cv::Scalar(upper.h, upper.s, upper.v),
                expected);
    int mismatches = 0;
    for (int i = 0; i < pixels.cols; ++i) {
      const cv::Vec3b& p = pixels.at<cv::Vec3b>(0, i);
      mismatches += box.contains(p[0], p[1], p[2]) != (expected.at<uchar>(0, i) != 0);
    }
    EXPECT_EQ(mismatches, 0) << describe(lower, upper);
  }
}

// Random frames of several sizes (widths not a multiple of 16 exercise the scalar tail):
// the band mask and the moments equal the lecture's pipeline.
TEST(LineDetector, MatchesTheLecturePipelineOnRandomFrames) {
  cv::RNG rng(5);
  for (const cv::Size size : {cv::Size(640, 480), cv::Size(333, 101), cv::Size(17, 9)}) {
    for (const auto& [lower, upper] : boundSets()) {
      cv::Mat frame(size, CV_8UC3);
      rng.fill(frame, cv::RNG::UNIFORM, 0, 256);
      const LineDetectorConfig config = withBounds(lower, upper);
      const LineDetector detector(config);
      const cv::Mat expected = referenceMask(frame, config);
      EXPECT_EQ(cv::countNonZero(detector.debugMask(frame) != expected), 0)
          << describe(lower, upper) << " " << size;

      const cv::Moments moments = cv::moments(expected);
      const BandMeasurement band = detector.detect(frame).band;
      EXPECT_EQ(band.pixel_count, static_cast<int>(moments.m00 / 255));
      if (moments.m00 > 0) {
        EXPECT_DOUBLE_EQ(band.centroid_x, moments.m10 / moments.m00);
        EXPECT_DOUBLE_EQ(band.centroid_y, moments.m01 / moments.m00);
      }
    }
  }
}

TEST(LineDetector, ValidatesItsConfiguration) {
  auto error_for = [](auto change) {
    LineDetectorConfig config;
    change(config);
    return validate(config);
  };
  EXPECT_EQ(error_for([](LineDetectorConfig& c) { c.lower.s = -1; }),
            "lower.s must be in [0, 255], got -1");
  EXPECT_EQ(error_for([](LineDetectorConfig& c) { c.upper.v = 256; }),
            "upper.v must be in [0, 255], got 256");
  EXPECT_EQ(error_for([](LineDetectorConfig& c) { c.lower.h = 45; }),
            "lower.h (45) must be <= upper.h (40); the box would match nothing");
  EXPECT_EQ(error_for([](LineDetectorConfig& c) { c.band.distance_m = 0.0; }),
            "band.distance_m must be > 0, got 0");
  EXPECT_EQ(error_for([](LineDetectorConfig& c) {
              c.look_ahead_enabled = true;
              c.look_ahead.distance_m = c.band.distance_m;
            }),
            "look_ahead.distance_m (0.46) must be beyond band.distance_m (0.46)");
  EXPECT_EQ(error_for([](LineDetectorConfig& c) { c.look_ahead.rows = 0; }),
            "look_ahead.rows must be in [1, 65536], got 0");
  EXPECT_EQ(error_for([](LineDetectorConfig& c) { c.min_pixels = 0; }),
            "min_pixels must be >= 1, got 0");
  EXPECT_EQ(error_for([](LineDetectorConfig& c) { c.max_width_fraction = 0.0; }),
            "max_width_fraction must be in (0, 1], got 0");
  EXPECT_EQ(error_for([](LineDetectorConfig& c) { c.blob_saturation_fraction = 1.5; }),
            "blob_saturation_fraction must be in [0, 1], got 1.5");
  EXPECT_EQ(error_for([](LineDetectorConfig& c) { c.floor_margin = 256; }),
            "floor_margin must be in [0, 255], got 256");
  EXPECT_EQ(error_for([](LineDetectorConfig& c) { c.floor_mads = -1.0; }),
            "floor_mads must be >= 0, got -1");
  EXPECT_EQ(error_for([](LineDetectorConfig& c) { c.line_width_m = 0.0; }),
            "line_width_m must be > 0, got 0");
  EXPECT_EQ(error_for([](LineDetectorConfig& c) { c.line_width_factor = -2.0; }),
            "line_width_factor must be >= 0, got -2");
  EXPECT_EQ(error_for([](LineDetectorConfig& c) { c.floor_mads = std::nan(""); }),
            "floor_mads must be >= 0, got nan");
  LineDetectorConfig bad;
  bad.band.rows = -5;
  EXPECT_THROW(LineDetector{bad}, std::invalid_argument);
}

TEST(LineDetector, DrawsBandMaskAndCentroid) {
  cv::Mat frame = greyFrame();
  paintStripe(frame, 300, 10, 0, 480);
  const LineDetector detector;
  const LineMeasurement m = detector.detect(frame);
  cv::Mat drawn = frame.clone();
  ASSERT_TRUE(detector.drawDebug(drawn, m));
  const cv::Vec3b red(0, 0, 255), green(0, 255, 0), magenta(255, 0, 255);
  EXPECT_EQ(drawn.at<cv::Vec3b>(370, 304), red);  // the filled centroid circle
  EXPECT_EQ(drawn.at<cv::Vec3b>(370, 304 + 19), red);
  EXPECT_EQ(drawn.at<cv::Vec3b>(360, 100), green);                          // band outline, top
  EXPECT_EQ(drawn.at<cv::Vec3b>(379, 600), green);                          // and bottom
  EXPECT_EQ(drawn.at<cv::Vec3b>(200, 305), frame.at<cv::Vec3b>(200, 305));  // off-band stripe
  cv::Mat far_from_circle = frame.clone();
  paintStripe(far_from_circle, 600, 2, 360, 380);
  cv::Mat drawn_far = far_from_circle.clone();
  ASSERT_TRUE(detector.drawDebug(drawn_far, detector.detect(far_from_circle)));
  EXPECT_EQ(drawn_far.at<cv::Vec3b>(370, 601), magenta);  // a line pixel of the band

  cv::Mat other_size = greyFrame(240, 320);
  EXPECT_FALSE(detector.drawDebug(other_size, m));
  cv::Mat grey_image(480, 640, CV_8UC1, cv::Scalar(0));
  EXPECT_FALSE(detector.drawDebug(grey_image, m));
}

}  // namespace
}  // namespace follow_bot
