#include "follow_bot/colour_blobs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>
#include <stdexcept>
#include <utility>

#include "blob_helpers.h"

namespace follow_bot {
namespace {

constexpr int kWidth = 640;
constexpr int kHeight = 480;

const cv::Scalar kFloorGrey(120, 120, 120);
const cv::Scalar kPureRed(0, 0, 255);
const cv::Scalar kPureGreen(0, 255, 0);
const cv::Scalar kPureBlue(255, 0, 0);

cv::Mat greyFrame() { return cv::Mat(kHeight, kWidth, CV_8UC3, kFloorGrey); }

// The BGR colour with this OpenCV HSV (H 0..179).
cv::Scalar bgrFromHsv(int h, int s, int v) {
  cv::Mat pixel(1, 1, CV_8UC3, cv::Scalar(h, s, v));
  cv::cvtColor(pixel, pixel, cv::COLOR_HSV2BGR);
  const cv::Vec3b bgr = pixel.at<cv::Vec3b>(0, 0);
  return cv::Scalar(bgr[0], bgr[1], bgr[2]);
}

// A disk shaded like a lit ball, full colour toward the top left and 60 % of it at the far
// edge (shaded = false: flat): the pixels whose centres are within `radius` of a sub-pixel
// centre.
void drawDisk(cv::Mat& frame, cv::Point2d centre, double radius, const cv::Scalar& colour,
              bool shaded = false) {
  for (int v = 0; v < frame.rows; ++v) {
    for (int u = 0; u < frame.cols; ++u) {
      const double dx = (u - centre.x) / radius;
      const double dy = (v - centre.y) / radius;
      if (dx * dx + dy * dy > 1.0) continue;
      const double light = std::clamp(0.5 - 0.5 * (dx + dy) / std::sqrt(2.0), 0.0, 1.0);
      const double shade = shaded ? 0.6 + 0.4 * light : 1.0;
      cv::Vec3b& pixel = frame.at<cv::Vec3b>(v, u);
      for (int c = 0; c < 3; ++c) pixel[c] = cv::saturate_cast<uchar>(colour[c] * shade);
    }
  }
}

using test::anyShape;  // as the lab worksheet's colour steps take it
using test::blobOf;

TEST(ColourNames, ParseGivesTheIssueDefaults) {
  const std::optional<ColourSpec> red = parseColourName("red");
  const std::optional<ColourSpec> green = parseColourName("green");
  const std::optional<ColourSpec> blue = parseColourName("blue");
  ASSERT_TRUE(red && green && blue);
  EXPECT_EQ(red->name, "red");
  EXPECT_EQ(red->hue_centre, 0);
  EXPECT_EQ(green->hue_centre, 60);
  EXPECT_EQ(blue->hue_centre, 120);
  EXPECT_EQ(green->sensitivity, 15);
  EXPECT_FALSE(parseColourName("yellow"));
  EXPECT_FALSE(parseColourName("Red"));
  EXPECT_FALSE(parseColourName(""));
}

TEST(ColourNames, SpecsFromNamesReportsTheUnknownName) {
  std::vector<ColourSpec> specs;
  EXPECT_EQ(colourSpecsFromNames({"green", "red"}, specs), "");
  ASSERT_EQ(specs.size(), 2u);
  EXPECT_EQ(specs[0].name, "green");
  EXPECT_EQ(specs[1].hue_centre, 0);
  EXPECT_EQ(colourSpecsFromNames({"blue", "purple"}, specs),
            "unknown colour name 'purple' (known: red, green, blue)");
  EXPECT_EQ(specs.size(), 2u) << "left unchanged on error";
}

TEST(ColourBlobConfig, DefaultIsValidAndHasThreeColours) {
  const ColourBlobConfig config;
  EXPECT_EQ(validate(config), "");
  ASSERT_EQ(config.colours.size(), 3u);
  EXPECT_EQ(config.colours[0].name, "red");
  EXPECT_EQ(config.colours[1].name, "green");
  EXPECT_EQ(config.colours[2].name, "blue");
}

TEST(ColourBlobConfig, ValidateNamesTheBadField) {
  // Each case changes a default config and names what validate() says of it.
  using Change = void (*)(ColourBlobConfig&);
  const std::pair<Change, const char*> cases[] = {
      {[](ColourBlobConfig& c) { c.colours[1].sensitivity = 95; },
       "colours[1] (green): sensitivity must be in [0, 90], got 95"},
      {[](ColourBlobConfig& c) { c.colours[0].sensitivity = -1; },
       "colours[0] (red): sensitivity must be in [0, 90], got -1"},
      {[](ColourBlobConfig& c) { c.colours[2].hue_centre = 180; },
       "colours[2] (blue): hue_centre must be in [0, 179], got 180"},
      {[](ColourBlobConfig& c) { c.colours[0].s_min = 256; },
       "colours[0] (red): s_min must be in [0, 255], got 256"},
      {[](ColourBlobConfig& c) { c.colours[0].v_min = -5; },
       "colours[0] (red): v_min must be in [0, 255], got -5"},
      {[](ColourBlobConfig& c) { c.colours[2].name = "green"; },
       "colours[2] (green): name is a duplicate"},
      {[](ColourBlobConfig& c) { c.colours[0].name = ""; },
       "colours[0] (): name must not be empty"},
      {[](ColourBlobConfig& c) { c.colours.clear(); }, "colours must name at least one colour"},
      {[](ColourBlobConfig& c) { c.min_area = -1.0; }, "min_area must be >= 0, got -1"},
      {[](ColourBlobConfig& c) { c.open_kernel = 4; },
       "open_kernel must be 0 (off) or an odd size, got 4"},
      {[](ColourBlobConfig& c) { c.close_kernel = -3; },
       "close_kernel must be 0 (off) or an odd size, got -3"},
      {[](ColourBlobConfig& c) { c.close_kernel = 1; }, ""},
      {[](ColourBlobConfig& c) {
         c.close_kernel = 1;
         c.roundness_tolerance = -0.1;
       },
       "roundness_tolerance must be in [0, 1], got -0.1"},
  };
  for (const auto& [change, expected] : cases) {
    ColourBlobConfig config;
    change(config);
    EXPECT_EQ(validate(config), expected);
  }
}

TEST(ColourBlobDetector, ConstructorRejectsBadConfig) {
  ColourBlobConfig config;
  config.min_area = -2.0;
  EXPECT_THROW(ColourBlobDetector{config}, std::invalid_argument);
}

TEST(ColourBlobDetector, LabelsEachColourAndLocatesItsCentroid) {
  struct Case {
    const char* name;
    cv::Scalar colour;
    bool shaded;
  };
  const Case cases[] = {
      {"red", kPureRed, false},
      {"green", kPureGreen, false},
      {"blue", kPureBlue, false},
      {"red", cv::Scalar(0, 0, 230), true},  // the rgb world's balls, lit
      {"green", cv::Scalar(0, 200, 0), true},
      {"blue", cv::Scalar(230, 0, 0), true},
      {"green", cv::Scalar(23, 69, 23), false},  // a shaded face of the dark-green dumpster
  };
  const ColourBlobDetector detector;
  const cv::Point2d centres[] = {{150.3, 130.7}, {330.0, 250.25}, {500.6, 360.1}};
  for (const Case& c : cases) {
    for (const cv::Point2d& centre : centres) {
      cv::Mat frame = greyFrame();
      drawDisk(frame, centre, 40.0, c.colour, c.shaded);
      const BlobResult result = detector.detect(frame);
      ASSERT_TRUE(result.ok()) << result.error;
      EXPECT_EQ(result.image_width, kWidth);
      EXPECT_EQ(result.image_height, kHeight);
      for (const ColourBlob& blob : result.colours) {
        const bool expected = blob.name == c.name;
        EXPECT_EQ(blob.found, expected) << c.name << " disk seen as " << blob.name;
        if (!expected || !blob.found) continue;
        EXPECT_EQ(blob.blob_count, 1);
        EXPECT_NEAR(blob.centroid.x, centre.x, 0.5) << c.name;
        EXPECT_NEAR(blob.centroid.y, centre.y, 0.5) << c.name;
        EXPECT_NEAR(blob.circle_centre.x, centre.x, 1.0);
        EXPECT_NEAR(blob.circle_centre.y, centre.y, 1.0);
        EXPECT_NEAR(blob.circle_radius, 40.0, 1.0);
        EXPECT_NEAR(blob.area, CV_PI * 40.0 * 40.0, 0.03 * CV_PI * 40.0 * 40.0);
        EXPECT_NEAR(blob.bounding_box.x, centre.x - 40.0, 1.0);
        EXPECT_NEAR(blob.bounding_box.br().x - 1, centre.x + 40.0, 1.0);
        EXPECT_NEAR(blob.bounding_box.y, centre.y - 40.0, 1.0);
        EXPECT_FALSE(blob.contour.empty());
      }
    }
  }
}

TEST(ColourBlobDetector, SeesTwoColoursAtOnce) {
  cv::Mat frame = greyFrame();
  drawDisk(frame, {200.0, 240.0}, 30.0, kPureGreen);
  drawDisk(frame, {450.0, 200.0}, 25.0, kPureRed);
  const BlobResult result = ColourBlobDetector().detect(frame);
  ASSERT_TRUE(blobOf(result, "green").found);
  ASSERT_TRUE(blobOf(result, "red").found);
  EXPECT_FALSE(blobOf(result, "blue").found);
  EXPECT_NEAR(blobOf(result, "green").centroid.x, 200.0, 0.5);
  EXPECT_NEAR(blobOf(result, "red").centroid.x, 450.0, 0.5);
  EXPECT_EQ(result.find("purple"), nullptr);
}

TEST(ColourBlobDetector, RedIsFoundOnBothSidesOfTheHueWrap) {
  const ColourBlobDetector detector;
  for (int hue : {0, 3, 173, 176, 179}) {
    cv::Mat frame = greyFrame();
    drawDisk(frame, {320.0, 240.0}, 30.0, bgrFromHsv(hue, 230, 220));
    const BlobResult result = detector.detect(frame);
    EXPECT_TRUE(blobOf(result, "red").found) << "hue " << hue;
    EXPECT_FALSE(blobOf(result, "green").found) << "hue " << hue;
    EXPECT_FALSE(blobOf(result, "blue").found) << "hue " << hue;
  }
  // Orange (sweets 6..9: in red's hue window, their blobs' median is not red), orange-yellow,
  // cyan-ish, purple, magenta, and pink (the harness's pink clutter, 165: also in the window).
  for (int hue : {6, 9, 15, 20, 30, 100, 140, 160, 165, 170}) {
    cv::Mat frame = greyFrame();
    drawDisk(frame, {320.0, 240.0}, 30.0, bgrFromHsv(hue, 230, 220));
    EXPECT_FALSE(blobOf(detector.detect(frame), "red").found) << "hue " << hue;
  }
}

TEST(ColourBlobDetector, RedIsFoundOnAWoodFloorInsideItsSensitivity) {
  // Wood at hue 15 (S 140) is inside red's window of 15: the ball and the floor made one blob,
  // orange by its median, and no red was found. Pixels above hue 10 do not count as red.
  const ColourBlobDetector detector;
  cv::Mat frame(480, 640, CV_8UC3, bgrFromHsv(15, 140, 180));
  drawDisk(frame, {320.0, 240.0}, 30.0, bgrFromHsv(0, 230, 220));
  const ColourBlob& red = blobOf(detector.detect(frame), "red");
  ASSERT_TRUE(red.found);
  EXPECT_NEAR(red.centroid.x, 320.0, 0.5);
  EXPECT_NEAR(red.centroid.y, 240.0, 0.5);
}

TEST(ColourBlobDetector, RedIsFoundOnAWoodFloorAsRedAsItsWindow) {
  // A redder wood (hue 8, S 116: the harsh red-stop sweep's member 003) is inside red's window
  // wholly, and the ball standing on it was one blob with the floor, never round: red was
  // found on a few frames only and the chaser drove on with it in view. The ball is far more
  // saturated than the wood; the blob's part more saturated than its Otsu split is the ball.
  const cv::Scalar wall(150, 150, 160), wood = bgrFromHsv(8, 116, 179);
  const cv::Point2d centre(210.5, 205.0);
  const double radius = 36.0;
  cv::Mat frame(480, 640, CV_8UC3, wall);
  frame.rowRange(200, 480).setTo(wood);
  cv::Mat plain_floor = frame.clone();
  drawDisk(frame, centre, radius, bgrFromHsv(0, 255, 203), true);
  cv::Mat noise(frame.size(), CV_16SC3);
  cv::randn(noise, 0.0, 4.0);
  for (cv::Mat* image : {&frame, &plain_floor}) {
    cv::Mat noisy;
    image->convertTo(noisy, CV_16SC3);
    noisy += noise;
    noisy.convertTo(*image, CV_8UC3);
  }
  const ColourBlobDetector detector;
  const ColourBlob& red = blobOf(detector.detect(frame), "red");
  ASSERT_TRUE(red.found);
  EXPECT_NEAR(red.circle_centre.x, centre.x, 1.5);
  EXPECT_NEAR(red.circle_centre.y, centre.y, 1.5);
  EXPECT_NEAR(red.circle_radius, radius, 1.5);
  EXPECT_FALSE(blobOf(detector.detect(plain_floor), "red").found) << "the wood alone is no ball";
}

TEST(ColourBlobDetector, HueWindowWrapsAtTheTopForCustomColours) {
  ColourBlobConfig config;
  config.colours = {ColourSpec{"magenta", 170, 15, 100, 40}};  // 155..179 and 0..5
  const ColourBlobDetector detector(config);
  for (int hue : {155, 179, 0, 5}) {
    cv::Mat frame = greyFrame();
    drawDisk(frame, {320.0, 240.0}, 30.0, bgrFromHsv(hue, 230, 220));
    EXPECT_TRUE(blobOf(detector.detect(frame), "magenta").found) << "hue " << hue;
  }
  for (int hue : {150, 6}) {
    cv::Mat frame = greyFrame();
    drawDisk(frame, {320.0, 240.0}, 30.0, bgrFromHsv(hue, 230, 220));
    EXPECT_FALSE(blobOf(detector.detect(frame), "magenta").found) << "hue " << hue;
  }
}

TEST(ColourBlobDetector, SaturationAndValueFloorsRejectGreyAndDark) {
  const ColourBlobDetector detector;
  cv::Mat frame = greyFrame();
  drawDisk(frame, {200.0, 240.0}, 40.0, bgrFromHsv(60, 80, 200));  // washed-out green
  // Nearly black green, below the default value floor (BeaconChaser.cfg's v_min).
  drawDisk(frame, {450.0, 240.0}, 40.0, bgrFromHsv(60, 255, ColourSpec().v_min - 10));
  EXPECT_FALSE(blobOf(detector.detect(frame), "green").found);
}

TEST(ColourBlobDetector, MinAreaIsRespected) {
  ColourBlobConfig config;
  config.min_area = 300.0;
  const ColourBlobDetector detector(config);
  cv::Mat frame = greyFrame();
  drawDisk(frame, {320.0, 240.0}, 9.0, kPureGreen);  // ~250 px^2
  EXPECT_FALSE(blobOf(detector.detect(frame), "green").found);
  EXPECT_EQ(blobOf(detector.detect(frame), "green").blob_count, 0);
  frame = greyFrame();
  drawDisk(frame, {320.0, 240.0}, 11.0, kPureGreen);  // ~380 px^2
  const ColourBlob green = blobOf(detector.detect(frame), "green");
  EXPECT_TRUE(green.found);
  EXPECT_GE(green.area, 300.0);
}

TEST(ColourBlobDetector, ChoosesTheLargestBlob) {
  cv::Mat frame = greyFrame();
  drawDisk(frame, {120.0, 240.0}, 20.0, kPureGreen);
  drawDisk(frame, {420.0, 200.0}, 45.0, kPureGreen);
  drawDisk(frame, {580.0, 400.0}, 30.0, kPureGreen);
  const BlobResult result = ColourBlobDetector().detect(frame);
  const ColourBlob green = blobOf(result, "green");
  ASSERT_TRUE(green.found);
  EXPECT_EQ(green.blob_count, 3);
  EXPECT_NEAR(green.centroid.x, 420.0, 0.5);
  EXPECT_NEAR(green.centroid.y, 200.0, 0.5);
  EXPECT_NEAR(green.circle_radius, 45.0, 1.0);
}

TEST(ColourBlobDetector, CleanUpRemovesSpecklesAndFillsPinholes) {
  cv::Mat frame = greyFrame();
  drawDisk(frame, {320.0, 240.0}, 50.0, kPureBlue);
  std::mt19937 random(7);
  std::uniform_int_distribution<int> column(0, kWidth - 1);
  std::uniform_int_distribution<int> row(0, kHeight - 1);
  for (int i = 0; i < 3000; ++i) {  // blue salt everywhere, grey pepper inside the disk
    frame.at<cv::Vec3b>(row(random), column(random)) = cv::Vec3b(255, 0, 0);
  }
  for (int i = 0; i < 200; ++i) {
    const double angle = i * 0.7;
    const double radius = 45.0 * (i % 10) / 10.0;
    frame.at<cv::Vec3b>(cvRound(240.0 + radius * std::sin(angle)),
                        cvRound(320.0 + radius * std::cos(angle))) = cv::Vec3b(120, 120, 120);
  }

  const ColourBlob cleaned = blobOf(ColourBlobDetector().detect(frame), "blue");
  ASSERT_TRUE(cleaned.found);
  EXPECT_EQ(cleaned.blob_count, 1);
  EXPECT_NEAR(cleaned.centroid.x, 320.0, 0.5);
  EXPECT_NEAR(cleaned.centroid.y, 240.0, 0.5);
  EXPECT_NEAR(cleaned.circle_radius, 50.0, 1.0);
  const cv::Mat mask = ColourBlobDetector().mask(frame, "blue");
  ASSERT_EQ(mask.type(), CV_8UC1);
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(300, 220, 41, 41))), 41 * 41) << "pinholes filled";
  EXPECT_LT(cv::countNonZero(mask), CV_PI * 52.0 * 52.0) << "specks removed";

  ColourBlobConfig raw;
  raw.open_kernel = 0;
  raw.close_kernel = 0;
  raw.min_area = 0.0;
  EXPECT_GT(blobOf(ColourBlobDetector(raw).detect(frame), "blue").blob_count, 1000);
}

TEST(ColourBlobDetector, WholeFrameOfOneColourIsOneBlob) {
  const cv::Mat frame(kHeight, kWidth, CV_8UC3, kPureGreen);
  const BlobResult result = ColourBlobDetector().detect(frame);
  const ColourBlob green = blobOf(result, "green");
  ASSERT_TRUE(green.found);
  EXPECT_EQ(green.blob_count, 1);
  EXPECT_EQ(green.bounding_box, cv::Rect(0, 0, kWidth, kHeight));
  EXPECT_DOUBLE_EQ(green.area, (kWidth - 1.0) * (kHeight - 1.0));
  EXPECT_NEAR(green.centroid.x, (kWidth - 1) / 2.0, 1e-9);
  EXPECT_NEAR(green.centroid.y, (kHeight - 1) / 2.0, 1e-9);
  EXPECT_FALSE(blobOf(result, "red").found);
  EXPECT_FALSE(blobOf(result, "blue").found);
}

TEST(ColourBlobDetector, NoBeaconInANoisyGreyScene) {
  cv::Mat frame = greyFrame();
  frame.rowRange(0, kHeight / 2).setTo(cv::Scalar(200, 200, 200));  // sky above the horizon
  cv::Mat noise(frame.size(), CV_16SC3);
  cv::randn(noise, 0.0, 8.0);
  frame.convertTo(frame, CV_16SC3);
  frame += noise;
  frame.convertTo(frame, CV_8UC3);
  const BlobResult result = ColourBlobDetector().detect(frame);
  ASSERT_TRUE(result.ok());
  ASSERT_EQ(result.colours.size(), 3u);
  for (const ColourBlob& blob : result.colours) {
    EXPECT_FALSE(blob.found) << blob.name;
    EXPECT_EQ(blob.area, 0.0);
    EXPECT_TRUE(blob.contour.empty());
  }
}

TEST(ColourBlobDetector, RejectsEmptyAndWrongTypeFramesWithoutThrowing) {
  const ColourBlobDetector detector;
  const cv::Mat frames[] = {cv::Mat(), cv::Mat(kHeight, kWidth, CV_8UC1, cv::Scalar(0)),
                            cv::Mat(kHeight, kWidth, CV_8UC4, kPureGreen),
                            cv::Mat(kHeight, kWidth, CV_32FC3, cv::Scalar(0, 1, 0))};
  for (const cv::Mat& frame : frames) {
    BlobResult result;
    EXPECT_NO_THROW(result = detector.detect(frame));
    EXPECT_FALSE(result.ok());
    EXPECT_FALSE(result.error.empty());
    ASSERT_EQ(result.colours.size(), 3u);
    for (const ColourBlob& blob : result.colours) EXPECT_FALSE(blob.found);
    EXPECT_TRUE(detector.mask(frame, "green").empty());
  }
  EXPECT_EQ(detector.detect(cv::Mat()).error, "empty frame");
  EXPECT_EQ(detector.detect(frames[1]).error, "expected a CV_8UC3 (BGR) frame, got type 0");
}

TEST(ColourBlobDetector, RectangleBoundingBoxIsExact) {
  cv::Mat frame = greyFrame();
  cv::rectangle(frame, cv::Rect(100, 150, 201, 121), kPureGreen, cv::FILLED);
  const ColourBlob green = blobOf(ColourBlobDetector(anyShape()).detect(frame), "green");
  ASSERT_TRUE(green.found);
  EXPECT_EQ(green.bounding_box, cv::Rect(100, 150, 201, 121));
  // The 3x3 elliptical (cross) opening trims each corner pixel: half a px^2 of contour area.
  EXPECT_DOUBLE_EQ(green.area, 200.0 * 120.0 - 4 * 0.5);
  EXPECT_NEAR(green.centroid.x, 200.0, 1e-9);
  EXPECT_NEAR(green.centroid.y, 210.0, 1e-9);
}

TEST(CircleFit, RecoversADiskAndMeasuresHowFarAPolygonStrays) {
  cv::Mat mask(kHeight, kWidth, CV_8UC1, cv::Scalar(0));
  cv::circle(mask, {300, 200}, 40, 255, cv::FILLED);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  const std::optional<CircleFit> disk = fitCircle(contours[0], mask.size());
  ASSERT_TRUE(disk);
  EXPECT_NEAR(disk->centre.x, 300.0, 0.05);
  EXPECT_NEAR(disk->centre.y, 200.0, 0.05);
  EXPECT_NEAR(disk->radius, 39.5, 0.1);  // boundary pixel centres lie half a pixel inside
  EXPECT_LT(disk->rms_error, 0.35);

  mask.setTo(0);
  cv::rectangle(mask, cv::Rect(100, 100, 61, 61), 255, cv::FILLED);
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  const std::optional<CircleFit> square = fitCircle(contours[0], mask.size());
  ASSERT_TRUE(square);
  EXPECT_NEAR(square->centre.x, 130.0, 0.05);
  EXPECT_GT(square->rms_error, 3.5);  // about 0.11 of its 34.6 px radius

  // Only border pixels, or a straight run: nothing to judge.
  mask.setTo(255);
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  EXPECT_FALSE(fitCircle(contours[0], mask.size()));
  EXPECT_FALSE(
      fitCircle({{10, 10}, {11, 10}, {12, 10}, {13, 10}, {14, 10}, {15, 10}}, mask.size()));
}

TEST(ColourBlobDetector, OnlyRoundBlobsAreBeaconsAndTheFramesEdgeDoesNotCount) {
  cv::Mat frame = greyFrame();
  drawDisk(frame, {200.0, 240.0}, 30.0, kPureGreen, true);  // a ball, smaller than the poster
  cv::rectangle(frame, cv::Rect(350, 100, 160, 90), kPureGreen, cv::FILLED);  // a poster
  drawDisk(frame, {-20.0, 100.0}, 40.0, kPureRed);  // a ball half out of view, on the left
  cv::rectangle(frame, cv::Rect(600, 300, 40, 60), kPureBlue, cv::FILLED);  // a box, cut off
  const BlobResult result = ColourBlobDetector().detect(frame);  // the beacon chaser's gate
  const ColourBlob green = blobOf(result, "green");
  ASSERT_TRUE(green.found);
  EXPECT_EQ(green.blob_count, 1);
  EXPECT_NEAR(green.centroid.x, 200.0, 0.5);
  EXPECT_TRUE(blobOf(result, "red").found);
  EXPECT_FALSE(blobOf(result, "blue").found);

  const BlobResult all = ColourBlobDetector(anyShape()).detect(frame);
  EXPECT_EQ(blobOf(all, "green").blob_count, 2);
  EXPECT_NEAR(blobOf(all, "green").centroid.x, 430.0, 0.5);  // the poster is the larger
  EXPECT_TRUE(blobOf(all, "blue").found);
}

// Real balls: a shadow of the ball's own hue below it (dark carpet passes v_min), a white
// highlight on its rim, a grey seam wider than the closing fills (from the rim, two thirds across:
// a seam right across splits the ball into two half disks, which are not found), a grey box
// hiding a third of it.
// Each is found at its centre and wins over a smaller (farther) whole ball; a tape line and a
// flat shadow-like blob alone are not balls.
TEST(ColourBlobDetector, RealBallsWithShadowHighlightSeamOrOcclusionAreFoundAndTheNearestWins) {
  const cv::Point2d centre(300.0, 220.0);
  constexpr double kRadius = 60.0;
  const auto spoil = [&](int kind, cv::Mat& frame) {
    switch (kind) {
      case 0:  // shadow: a flat dark-red ellipse under the ball
        cv::ellipse(frame, cv::Point(300, 280), cv::Size(90, 22), 0.0, 0.0, 360.0,
                    cv::Scalar(0, 0, 60), cv::FILLED);
        break;
      case 1:  // highlight on the rim
        cv::circle(frame, cv::Point(262, 178), 18, cv::Scalar(250, 250, 250), cv::FILLED);
        break;
      case 2:  // seam
        cv::line(frame, cv::Point(230, 150), cv::Point(330, 250), kFloorGrey, 7);
        break;
      case 3:  // occluded by a box
        cv::rectangle(frame, cv::Rect(330, 100, 200, 250), kFloorGrey, cv::FILLED);
        break;
    }
  };
  const ColourBlobDetector detector;
  for (int kind = 0; kind < 4; ++kind) {
    cv::Mat frame = greyFrame();
    drawDisk(frame, {520.0, 400.0}, 35.0, kPureRed, true);  // a farther whole ball
    if (kind == 0) spoil(kind, frame);                      // the shadow lies behind the ball
    drawDisk(frame, centre, kRadius, cv::Scalar(0, 0, 230), true);
    if (kind != 0) spoil(kind, frame);
    const ColourBlob red = blobOf(detector.detect(frame), "red");
    ASSERT_TRUE(red.found) << "case " << kind;
    ASSERT_GE(red.circles.size(), 1u);
    EXPECT_NEAR(red.circles[0][0], centre.x, 2.0) << "case " << kind;
    EXPECT_NEAR(red.circles[0][1], centre.y, 2.0) << "case " << kind;
    EXPECT_NEAR(red.circles[0][2], kRadius, 2.5) << "case " << kind;
    EXPECT_LT(cv::norm(cv::Point2f(red.circle_centre) - cv::Point2f(centre)), 8.0)
        << "case " << kind << ": the reported blob is the near ball";
  }

  cv::Mat frame = greyFrame();
  cv::rectangle(frame, cv::Rect(40, 300, 400, 20), kPureRed, cv::FILLED);  // tape
  cv::ellipse(frame, cv::Point(400, 150), cv::Size(100, 18), 10.0, 0.0, 360.0, kPureBlue,
              cv::FILLED);  // a flat blob, as a shadow's outline
  const BlobResult result = detector.detect(frame);
  EXPECT_FALSE(blobOf(result, "red").found);
  EXPECT_FALSE(blobOf(result, "blue").found);
}

// The image circle of a ball of `radius` m resting on the floor `distance` m ahead of a level
// camera (the default one, pitch 0) on its optical axis: its silhouette's ends on the image's
// middle column are the rays tangent to the ball, theta -+ alpha below the horizontal.
std::pair<cv::Point2d, double> floorBallCircle(const CameraGeometry& camera, double distance,
                                               double radius) {
  const double drop = camera.height_m - radius;
  const double theta = std::atan2(drop, distance);
  const double alpha = std::asin(radius / std::hypot(drop, distance));
  const double top = camera.cy + camera.fy * std::tan(theta - alpha);
  const double bottom = camera.cy + camera.fy * std::tan(theta + alpha);
  return {{camera.cx, 0.5 * (top + bottom)}, 0.5 * (bottom - top)};
}

CameraGeometry levelCamera() {
  CameraGeometry camera;
  camera.pitch_rad = 0.0;
  return camera;
}

TEST(FloorBallRadius, RecoversTheRadiusOfABallOnTheFloorAndNoneAboveTheHorizon) {
  const CameraGeometry camera = levelCamera();
  for (const double radius : {0.1, 0.2, 0.25}) {
    for (const double distance : {0.8, 2.0, 4.0}) {
      const auto [centre, radius_px] = floorBallCircle(camera, distance, radius);
      const std::optional<double> implied = floorBallRadius(camera, centre, radius_px);
      ASSERT_TRUE(implied) << radius << " m at " << distance << " m";
      EXPECT_NEAR(*implied, radius, 1e-9) << radius << " m at " << distance << " m";
    }
  }
  // A 20 px disk centred 40 px above the horizon (a wall picture): no ball on the floor.
  EXPECT_FALSE(floorBallRadius(camera, {320.0, camera.cy - 40.0}, 20.0));
  EXPECT_FALSE(floorBallRadius(camera, {320.0, 300.0}, 0.0));
}

TEST(ColourBlobDetector, FloorBallGateKeepsOnlyBallsOfTheBeaconsSize) {
  const CameraGeometry camera = levelCamera();
  cv::Mat frame = greyFrame();
  const auto [beacon, beacon_px] = floorBallCircle(camera, 2.0, 0.2);
  drawDisk(frame, beacon, beacon_px, kPureGreen, true);
  const auto [small, small_px] = floorBallCircle(camera, 1.0, 0.12);  // larger in the view
  drawDisk(frame, small + cv::Point2d(-200.0, 0.0), small_px, kPureGreen, true);
  drawDisk(frame, {500.0, 150.0}, 30.0, kPureRed);  // a round picture on a wall
  ColourBlobConfig balls;
  balls.floor_ball = ColourBlobConfig::FloorBall{0.2, 0.3, camera};
  const BlobResult result = ColourBlobDetector(balls).detect(frame);
  const ColourBlob green = blobOf(result, "green");
  ASSERT_TRUE(green.found);
  EXPECT_EQ(green.blob_count, 1);
  EXPECT_NEAR(green.centroid.x, beacon.x, 0.5);
  EXPECT_FALSE(blobOf(result, "red").found);

  const BlobResult all = ColourBlobDetector().detect(frame);  // any size
  EXPECT_EQ(blobOf(all, "green").blob_count, 2);
  EXPECT_NEAR(blobOf(all, "green").centroid.x, small.x - 200.0, 0.5);  // the larger
  EXPECT_TRUE(blobOf(all, "red").found);

  balls.floor_ball->radius_m = -0.2;
  EXPECT_EQ(validate(balls), "floor_ball.radius_m must be > 0, got -0.2");
}

TEST(ColourBlobDetector, MaskOfUnknownColourIsEmpty) {
  const cv::Mat frame = greyFrame();
  EXPECT_TRUE(ColourBlobDetector().mask(frame, "purple").empty());
  EXPECT_EQ(cv::countNonZero(ColourBlobDetector().mask(frame, "red")), 0);
}

}  // namespace
}  // namespace follow_bot
