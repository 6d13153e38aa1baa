#include "follow_bot/beacon_controller.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "blob_helpers.h"

namespace follow_bot {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kWidth = 640;
constexpr int kHeight = 480;
const cv::Scalar kFloorGrey(120, 120, 120);
const cv::Scalar kSkyGrey(200, 200, 200);
const cv::Scalar kDumpsterGreen(40, 90, 30);  // the dumpster world's box, BGR

double degrees(double deg) { return deg * kPi / 180.0; }

// The harness camera as the rgb and dumpster worlds set it up: level, 0.3 m up.
CameraGeometry levelCamera() {
  CameraGeometry camera;
  camera.pitch_rad = 0.0;
  return camera;
}

// ---- A small independent renderer, written from the conventions in ground_projection.h ----

struct Pose {
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;
};

// A box standing on the floor, as in the harness's worlds: `length` along `yaw`, `width`
// across it.
struct Box {
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;
  double length = 1.0;
  double width = 1.8;
  double height = 1.2;
};

struct Sphere {
  cv::Point3d centre;  // world
  double radius = 0.2;
};

cv::Point3d worldToBase(const Pose& robot, const cv::Point3d& world) {
  const double dx = world.x - robot.x;
  const double dy = world.y - robot.y;
  const double c = std::cos(robot.yaw);
  const double s = std::sin(robot.yaw);
  return cv::Point3d(c * dx + s * dy, -s * dx + c * dy, world.z);
}

// Optical frame: x right, y down, z along the axis.
cv::Point3d baseToOptical(const CameraGeometry& camera, const cv::Point3d& base) {
  const double p = camera.pitch_rad;
  const cv::Vec3d axis(std::cos(p), 0.0, -std::sin(p));
  const cv::Vec3d right(0.0, -1.0, 0.0);
  const cv::Vec3d down = axis.cross(right);
  const cv::Vec3d d(base.x - camera.x_offset_m, base.y, base.z - camera.height_m);
  return cv::Point3d(d.dot(right), d.dot(down), d.dot(axis));
}

cv::Point2d projectOptical(const CameraGeometry& camera, const cv::Point3d& optical) {
  return cv::Point2d(camera.cx + camera.fx * optical.x / optical.z,
                     camera.cy + camera.fy * optical.y / optical.z);
}

// Floor and sky: the horizon is the row where the optical rays turn horizontal.
cv::Mat emptyScene(const CameraGeometry& camera) {
  cv::Mat frame(kHeight, kWidth, CV_8UC3, kFloorGrey);
  const int horizon = static_cast<int>(std::clamp(
      std::ceil(camera.cy - camera.fy * std::tan(camera.pitch_rad)), 0.0, 1.0 * kHeight));
  frame.rowRange(0, horizon).setTo(kSkyGrey);
  return frame;
}

// Draws the box's visible faces as the harness does (anti-aliased convex polygons at 1/16 px,
// Lambert-shaded), so edge pixels have the harness's partial coverage. All corners must be in
// front of the camera.
void drawBox(cv::Mat& frame, const CameraGeometry& camera, const Pose& robot, const Box& box,
             const cv::Scalar& colour) {
  const double c = std::cos(box.yaw);
  const double s = std::sin(box.yaw);
  std::array<cv::Point3d, 8> corners;  // bottom ring then top ring, counter-clockwise
  const double ring[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  for (int i = 0; i < 8; ++i) {
    const double along = ring[i % 4][0] * box.length / 2.0;
    const double across = ring[i % 4][1] * box.width / 2.0;
    corners[i] = cv::Point3d(box.x + c * along - s * across, box.y + s * along + c * across,
                             i < 4 ? 0.0 : box.height);
  }
  struct Face {
    std::array<int, 4> corners;
    cv::Vec3d normal;  // box frame
  };
  const Face faces[] = {{{0, 1, 2, 3}, {0, 0, -1}}, {{4, 5, 6, 7}, {0, 0, 1}},
                        {{1, 2, 6, 5}, {1, 0, 0}},  {{0, 3, 7, 4}, {-1, 0, 0}},
                        {{2, 3, 7, 6}, {0, 1, 0}},  {{0, 1, 5, 4}, {0, -1, 0}}};
  const cv::Vec3d light = cv::normalize(cv::Vec3d(-0.5, 0.3, 1.0));
  const cv::Point3d camera_world(robot.x + std::cos(robot.yaw) * camera.x_offset_m,
                                 robot.y + std::sin(robot.yaw) * camera.x_offset_m,
                                 camera.height_m);
  for (const Face& face : faces) {
    const cv::Vec3d normal(c * face.normal[0] - s * face.normal[1],
                           s * face.normal[0] + c * face.normal[1], face.normal[2]);
    cv::Point3d centre(0, 0, 0);
    for (int i : face.corners) centre += corners[i] * 0.25;
    const cv::Point3d to_camera = camera_world - centre;
    if (normal.dot(cv::Vec3d(to_camera.x, to_camera.y, to_camera.z)) <= 0.0) continue;
    std::vector<cv::Point> polygon;
    for (int i : face.corners) {
      const cv::Point3d optical = baseToOptical(camera, worldToBase(robot, corners[i]));
      if (optical.z < 0.02) throw std::runtime_error("box corner behind the camera");
      const cv::Point2d uv = projectOptical(camera, optical);
      polygon.emplace_back(cvRound(uv.x * 16.0), cvRound(uv.y * 16.0));
    }
    const double shade = 0.6 + 0.4 * std::max(0.0, normal.dot(light));
    cv::fillConvexPoly(frame, polygon, colour * shade, cv::LINE_AA, 4);
  }
}

// The harness's score: horizontal distance from the base centre to the box's rectangle.
double distanceToFootprint(const Pose& robot, const Box& box) {
  const double dx = robot.x - box.x;
  const double dy = robot.y - box.y;
  const double along = std::abs(dx * std::cos(box.yaw) + dy * std::sin(box.yaw)) - box.length / 2;
  const double across = std::abs(-dx * std::sin(box.yaw) + dy * std::cos(box.yaw)) - box.width / 2;
  return std::hypot(std::max(along, 0.0), std::max(across, 0.0));
}

// The harness's bearing: |angle from the robot's heading to the object's centre|, degrees.
double bearingToCentreDeg(const Pose& robot, double x, double y) {
  const double bearing = std::atan2(y - robot.y, x - robot.x) - robot.yaw;
  return std::abs(std::remainder(bearing, 2.0 * kPi)) * 180.0 / kPi;
}

// A sphere's exact silhouette, pixel centres inside the cone of rays that meet it. Through the
// camera's lens, if it has one: each raw pixel centre's ray is that of its rectified pixel.
void drawSphere(cv::Mat& frame, const CameraGeometry& camera, const Pose& robot,
                const Sphere& sphere, const cv::Scalar& colour) {
  const cv::Point3d c = baseToOptical(camera, worldToBase(robot, sphere.centre));
  const double k = c.dot(c) - sphere.radius * sphere.radius;
  std::vector<cv::Point2d> pixels;
  for (int v = 0; v < frame.rows; ++v) {
    for (int u = 0; u < frame.cols; ++u) pixels.emplace_back(u, v);
  }
  pixels = rectifyPixels(camera, pixels);
  for (int v = 0; v < frame.rows; ++v) {
    for (int u = 0; u < frame.cols; ++u) {
      const cv::Point2d& pixel = pixels[v * frame.cols + u];
      const cv::Point3d ray((pixel.x - camera.cx) / camera.fx, (pixel.y - camera.cy) / camera.fy,
                            1.0);
      const double along = ray.dot(c);
      if (along > 0.0 && along * along > ray.dot(ray) * k) {
        frame.at<cv::Vec3b>(v, u) = cv::Vec3b(colour[0], colour[1], colour[2]);
      }
    }
  }
}

using test::blobOf;

// The detector as an approach node configures it for a box target (settings.cpp): a box is not
// round, so no roundness gate.
ColourBlobConfig boxTargetDetector() { return test::anyShape(); }

// The ground-contact range reads whole rows, so allow 0.6 of a row's worth near `range`: the
// row of a floor point d ahead is about cy + fy * h / d, so d changes by about
// (d^2 + h^2) / (fy * h) per row.
double groundRangeTolerance(const CameraGeometry& camera, double range) {
  return 0.6 * (range * range + camera.height_m * camera.height_m) / (camera.fy * camera.height_m);
}

// ---- Range estimates -----------------------------------------------------------------------

TEST(BeaconShape, ParseAndToStringRoundTrip) {
  for (BeaconShape shape : {BeaconShape::kSphere, BeaconShape::kBox}) {
    EXPECT_EQ(parseBeaconShape(toString(shape)), shape);
  }
  EXPECT_FALSE(parseBeaconShape("cube"));
  BeaconObject object;
  EXPECT_EQ(validate(object), "");
  object.size_m = 0.0;
  EXPECT_EQ(validate(object), "size_m must be > 0, got 0");
}

TEST(RangeFromWidth, IsFocalTimesWidthOverPixels) {
  EXPECT_DOUBLE_EQ(*rangeFromWidth(554.256, 1.8, 554.256 * 1.8 / 4.0), 4.0);
  EXPECT_FALSE(rangeFromWidth(554.256, 1.8, 0.0));
  EXPECT_FALSE(rangeFromWidth(554.256, -1.0, 10.0));
  EXPECT_FALSE(rangeFromWidth(kNaN, 1.8, 10.0));
  EXPECT_FALSE(rangeFromWidth(554.256, 1.8, 1e-320));  // would overflow to inf
}

TEST(RangeEstimate, BoxRangesFromWidthAndGroundContactMatchTheFootprint) {
  const ColourBlobDetector detector(boxTargetDetector());
  BeaconObject object;  // a box with a 1.8 m face
  for (double gap : {1.7, 2.0, 3.0, 4.0, 6.0}) {
    const Box box{gap + 0.5, 0.0, kPi / 2.0, 1.8, 1.0, 1.2};  // the dumpster, face-on
    const Pose robot;
    const CameraGeometry camera = levelCamera();
    cv::Mat frame = emptyScene(camera);
    drawBox(frame, camera, robot, box, kDumpsterGreen);
    const BlobResult blobs = detector.detect(frame);
    const ColourBlob green = blobOf(blobs, "green");
    ASSERT_TRUE(green.found) << gap;
    const RangeEstimate range = estimateRange(green, kWidth, kHeight, camera, object);
    ASSERT_TRUE(range.from_size && range.from_ground) << gap;
    EXPECT_NEAR(*range.from_size, gap, 0.01 * gap) << gap;
    EXPECT_NEAR(*range.from_ground, gap, groundRangeTolerance(camera, gap)) << gap;
    EXPECT_EQ(range.best(), range.from_ground);

    // The ground range is pixelToGround at the lower edge of the bounding box's last row.
    const cv::Rect& bounds = green.bounding_box;
    const std::optional<cv::Point2d> floor =
        pixelToGround(camera, camera.cx, bounds.y + bounds.height - 1);
    ASSERT_TRUE(floor);
    EXPECT_NEAR(*range.from_ground, floor->x, 1e-6) << gap;
  }
}

TEST(RangeEstimate, BoxGroundRangeWorksWithPitchAndOffsetAndObliqueViews) {
  const ColourBlobDetector detector(boxTargetDetector());
  BeaconObject object;
  object.size_m = 1.0;
  CameraGeometry camera;  // pitched 20 deg down
  camera.x_offset_m = 0.12;
  const Box box{2.0, 0.3, 0.4, 0.8, 1.0, 0.5};
  for (const Pose& robot : {Pose{0.0, 0.0, 0.0}, Pose{0.5, -0.4, 0.3}, Pose{0.2, 0.8, -0.2}}) {
    cv::Mat frame = emptyScene(camera);
    drawBox(frame, camera, robot, box, kDumpsterGreen);
    const ColourBlob green = blobOf(detector.detect(frame), "green");
    ASSERT_TRUE(green.found);
    const RangeEstimate range = estimateRange(green, kWidth, kHeight, camera, object);
    ASSERT_TRUE(range.from_ground);
    const double truth = distanceToFootprint(robot, box);
    EXPECT_NEAR(*range.from_ground, truth, groundRangeTolerance(camera, truth))
        << robot.x << ", " << robot.y;
  }
}

TEST(RangeEstimate, BoxCutByTheFrameHasNoSizeRangeAndBottomCutHasNoGroundRange) {
  const ColourBlobDetector detector(boxTargetDetector());
  const CameraGeometry camera = levelCamera();
  const Box box{1.0 + 0.5, 0.0, kPi / 2.0, 1.8, 1.0, 1.2};  // 1 m away: wider than the frame
  cv::Mat frame = emptyScene(camera);
  drawBox(frame, camera, Pose(), box, kDumpsterGreen);
  const ColourBlob green = blobOf(detector.detect(frame), "green");
  ASSERT_TRUE(green.found);
  RangeEstimate range = estimateRange(green, kWidth, kHeight, camera, BeaconObject());
  EXPECT_FALSE(range.from_size);
  ASSERT_TRUE(range.from_ground);
  EXPECT_NEAR(*range.from_ground, 1.0, 0.005);

  const Box near_box{0.5 + 0.5, 0.0, kPi / 2.0, 1.8, 1.0, 1.2};  // bottom edge below the frame
  frame = emptyScene(camera);
  drawBox(frame, camera, Pose(), near_box, kDumpsterGreen);
  range = estimateRange(blobOf(detector.detect(frame), "green"), kWidth, kHeight, camera,
                        BeaconObject());
  EXPECT_FALSE(range.from_size);
  EXPECT_FALSE(range.from_ground);
  EXPECT_FALSE(range.best());
}

// The dumpster world's box with its near face `gap` metres ahead of the origin, face-on.
Box dumpsterAt(double gap, double lateral = 0.0) {
  return Box{gap + 0.5, lateral, kPi / 2.0, 1.8, 1.0, 1.2};
}

cv::Point2d centreInBase(const Pose& robot, const Box& box) {
  const cv::Point3d centre = worldToBase(robot, cv::Point3d(box.x, box.y, 0.0));
  return cv::Point2d(centre.x, centre.y);
}

TEST(BoxCentre, FindsTheCentreOfABoxFromTheEndsOfItsFaceInView) {
  const ColourBlobDetector detector(boxTargetDetector());
  const BeaconObject object;  // the dumpster: 1.8 m face, 1.0 m deep
  int one_side_cut = 0;
  int whole = 0;
  for (const CameraGeometry& camera : {levelCamera(), CameraGeometry()}) {  // level, 20 deg down
    for (double gap : {0.9, 1.2, 1.6, 2.2}) {
      for (double lateral : {-0.3, 0.0, 0.2}) {
        for (double yaw_deg : {-20.0, -8.0, 0.0, 8.0, 20.0}) {
          const Pose robot{0.0, 0.0, degrees(yaw_deg)};
          const Box box = dumpsterAt(gap, lateral);
          cv::Mat frame = emptyScene(camera);
          drawBox(frame, camera, robot, box, kDumpsterGreen);
          const ColourBlob green = blobOf(detector.detect(frame), "green");
          ASSERT_TRUE(green.found);
          const cv::Rect& bounds = green.bounding_box;
          const bool cut_left = bounds.x <= 0;
          const bool cut_right = bounds.x + bounds.width >= kWidth;
          const std::optional<BoxFace> face = boxFace(green, kWidth, kHeight, camera);
          const std::optional<cv::Point2d> centre =
              face ? boxCentre(*face, cut_left, cut_right, object) : std::nullopt;
          const std::string where = std::to_string(gap) + " m, lateral " + std::to_string(lateral) +
                                    ", yaw " + std::to_string(yaw_deg);
          if (bounds.y + bounds.height >= kHeight) {
            EXPECT_FALSE(face) << where;
            continue;
          }
          if (cut_left && cut_right) {
            EXPECT_FALSE(centre) << where;
            continue;
          }
          ++(cut_left == cut_right ? whole : one_side_cut);
          ASSERT_TRUE(centre) << where;
          // Across within 1 cm; along the view, within the ground range's row quantisation.
          const cv::Point2d truth = centreInBase(robot, box);
          EXPECT_NEAR(centre->x, truth.x, std::max(0.01, groundRangeTolerance(camera, gap)))
              << where;
          EXPECT_NEAR(centre->y, truth.y, 0.01) << where;
        }
      }
    }
  }
  EXPECT_GE(one_side_cut, 30);
  EXPECT_GE(whole, 5);

  // From beside the box its 1.0 m side faces the camera: not the 1.8 m face, no centre.
  const CameraGeometry camera = levelCamera();
  const Pose beside{2.5, 2.6, -kPi / 2.0};
  cv::Mat frame = emptyScene(camera);
  drawBox(frame, camera, beside, dumpsterAt(2.0), kDumpsterGreen);
  const ColourBlob green = blobOf(detector.detect(frame), "green");
  const std::optional<BoxFace> face = boxFace(green, kWidth, kHeight, camera);
  ASSERT_TRUE(face);
  EXPECT_FALSE(boxCentre(*face, false, false, object));
  BeaconObject side = object;
  std::swap(side.size_m, side.depth_m);
  EXPECT_TRUE(boxCentre(*face, false, false, side)) << "but the 1.0 m face of a 1.0 x 1.8 box";
}

TEST(BoxFace, AnotherObjectOfTheColourTouchingTheSilhouetteIsLeftOut) {
  const ColourBlobDetector detector(boxTargetDetector());
  const CameraGeometry camera = levelCamera();
  const Pose robot{0.0, 0.0, degrees(12.0)};  // the dumpster's right edge out of the frame
  const Box dumpster = dumpsterAt(1.3);
  // A small box of the same green beside the dumpster and 0.4 m behind its face, seen just
  // left of its left edge, as the harsh profile's clutter may stand.
  const Box clutter{1.85, 1.37, 0.3, 0.25, 0.25, 0.6};
  cv::Mat alone = emptyScene(camera);
  drawBox(alone, camera, robot, dumpster, kDumpsterGreen);
  cv::Mat frame = emptyScene(camera);
  drawBox(frame, camera, robot, clutter, kDumpsterGreen);  // the farther first
  drawBox(frame, camera, robot, dumpster, kDumpsterGreen);
  const ColourBlob dumpster_only = blobOf(detector.detect(alone), "green");
  const ColourBlob merged = blobOf(detector.detect(frame), "green");
  ASSERT_GT(merged.bounding_box.width, dumpster_only.bounding_box.width + 10)
      << "the clutter joins the dumpster's blob";
  const std::optional<BoxFace> face = boxFace(merged, kWidth, kHeight, camera);
  ASSERT_TRUE(face);
  const std::optional<cv::Point2d> centre = boxCentre(*face, false, true, BeaconObject());
  ASSERT_TRUE(centre);
  const cv::Point2d truth = centreInBase(robot, dumpster);
  EXPECT_NEAR(centre->x, truth.x, 0.01);
  EXPECT_NEAR(centre->y, truth.y, 0.01);
}

TEST(SphereCentreFromCircle, OnAxisIsRadiusOverSinOfTheAngularRadius) {
  CameraGeometry camera = levelCamera();
  camera.height_m = 0.5;
  for (double distance : {0.5, 1.0, 3.0, 8.0}) {
    const double alpha = std::asin(0.2 / distance);
    const double radius_px = camera.fx * std::tan(alpha);
    const std::optional<cv::Point3d> centre =
        sphereCentreFromCircle(camera, {camera.cx, camera.cy}, radius_px, 0.2);
    ASSERT_TRUE(centre);
    EXPECT_NEAR(centre->x, distance, 1e-9);
    EXPECT_NEAR(centre->y, 0.0, 1e-9);
    EXPECT_NEAR(centre->z, 0.5, 1e-9);
  }
  EXPECT_FALSE(sphereCentreFromCircle(camera, {320, 240}, 0.0, 0.2));
  EXPECT_FALSE(sphereCentreFromCircle(camera, {320, 240}, 10.0, 0.0));
  EXPECT_FALSE(sphereCentreFromCircle(camera, {kNaN, 240}, 10.0, 0.2));
  camera.fx = 0.0;
  EXPECT_FALSE(sphereCentreFromCircle(camera, {320, 240}, 10.0, 0.2));
}

TEST(RangeEstimate, SphereRangeFromSizeIsWithinOnePercentOnARenderedSilhouette) {
  const ColourBlobDetector detector;
  BeaconObject ball;
  ball.shape = BeaconShape::kSphere;
  ball.size_m = 0.2;
  CameraGeometry pitched;
  pitched.pitch_rad = degrees(10.0);
  pitched.x_offset_m = -0.1;
  struct Case {
    CameraGeometry camera;
    Sphere sphere;
  };
  const Case cases[] = {
      {levelCamera(), {{1.2, 0.0, 0.2}, 0.2}},    // the stop point of Exercise 10
      {levelCamera(), {{3.0, 1.0, 0.2}, 0.2}},    // the rgb world's red ball
      {levelCamera(), {{3.5, 0.0, 0.2}, 0.2}},    // green
      {levelCamera(), {{3.0, -1.0, 0.2}, 0.2}},   // blue
      {levelCamera(), {{1.5, -0.55, 0.2}, 0.2}},  // well off-axis: an elongated ellipse
      {pitched, {{1.6, 0.4, 0.2}, 0.2}},
  };
  for (const Case& c : cases) {
    cv::Mat frame = emptyScene(c.camera);
    drawSphere(frame, c.camera, Pose(), c.sphere, cv::Scalar(0, 200, 0));
    const ColourBlob green = blobOf(detector.detect(frame), "green");
    ASSERT_TRUE(green.found);
    const RangeEstimate range = estimateRange(green, kWidth, kHeight, c.camera, ball);
    EXPECT_FALSE(range.from_ground) << "a ball's outline does not touch the floor";
    ASSERT_TRUE(range.from_size) << c.sphere.centre.x << ", " << c.sphere.centre.y << " box "
                                 << green.bounding_box;
    const double truth = std::hypot(c.sphere.centre.x, c.sphere.centre.y) - c.sphere.radius;
    EXPECT_NEAR(*range.from_size, truth, 0.01 * truth)
        << c.sphere.centre.x << ", " << c.sphere.centre.y;
    const std::optional<cv::Point3d> centre = sphereCentreFromCircle(
        c.camera, cv::Point2d(green.circle_centre), green.circle_radius, 0.2);
    ASSERT_TRUE(centre);
    EXPECT_NEAR(centre->z, 0.2, 0.02);
  }
}

TEST(RangeEstimate, SphereCutByTheFrameOrNotFoundHasNoRange) {
  BeaconObject ball;
  ball.shape = BeaconShape::kSphere;
  ball.size_m = 0.2;
  const CameraGeometry camera = levelCamera();
  cv::Mat frame = emptyScene(camera);
  drawSphere(frame, camera, Pose(), {{2.0, 1.15, 0.2}, 0.2}, cv::Scalar(0, 200, 0));
  const ColourBlob green = blobOf(ColourBlobDetector().detect(frame), "green");
  ASSERT_TRUE(green.found);
  EXPECT_EQ(green.bounding_box.x, 0);
  EXPECT_FALSE(estimateRange(green, kWidth, kHeight, camera, ball).best());
  EXPECT_FALSE(estimateRange(ColourBlob(), kWidth, kHeight, camera, ball).best());
}

// The level camera through the harness's turtlebot3 lens (harness/src/harness/camera.py):
// visible barrel distortion, P = K.
CameraGeometry barrelCamera() {
  CameraGeometry camera = levelCamera();
  const cv::Matx33d k(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  camera.lens = CameraLens{k, {-0.28, 0.07, 0.0, 0.0, 0.0}, cv::Matx33d::eye()};
  return camera;
}

// The green ball of the follow-green scenario seen by `camera` from the origin (raw frames when
// the camera has a lens).
BlobResult lookAtBall(const CameraGeometry& camera, const cv::Point3d& centre) {
  cv::Mat frame = emptyScene(camera);
  drawSphere(frame, camera, Pose(), {centre, 0.2}, cv::Scalar(0, 200, 0));
  return ColourBlobDetector().detect(frame);
}

TEST(RectifyBlob, WithoutALensIsTheBlobsOwn) {
  const ColourBlob green = blobOf(lookAtBall(levelCamera(), {1.0, 0.3, 0.2}), "green");
  ASSERT_TRUE(green.found);
  const RectifiedBlob rectified = rectifyBlob(green, levelCamera(), {kWidth, kHeight});
  EXPECT_EQ(rectified.area, green.area);
  EXPECT_EQ(rectified.area_in_frame, green.area);
  EXPECT_EQ(rectified.centroid, green.centroid);
  EXPECT_EQ(rectified.circle_centre, cv::Point2d(green.circle_centre));
  EXPECT_EQ(rectified.circle_radius, green.circle_radius);
  EXPECT_EQ(rectified.width, green.bounding_box.width);
  EXPECT_EQ(rectified.contour.size(), green.contour.size());
}

TEST(RectifyBlob, ARawFrameThroughTheLensMeasuresAsTheRectifiedFrame) {
  // The ball near where follow-green holds (0.50 m from its surface, cut by the frame's bottom
  // edge), off the axis and farther: the rectified contour of the raw blob has the pinhole
  // blob's area inside the frame, and where the pinhole frame does not cut the ball its area,
  // centroid and size, while the raw blob is 5-16 % smaller. The lens sees wider: where the
  // pinhole frame cuts the ball, the rectified contour encloses more.
  struct Case {
    cv::Point3d centre;
    double raw_shrink_min;  // 1 - raw area / pinhole area, at least
    bool cut;               // by the pinhole frame
  };
  const Case cases[] = {{{0.67, 0.0, 0.2}, 0.05, true},
                        {{0.72, 0.2, 0.2}, 0.13, true},
                        {{1.5, -0.55, 0.2}, 0.15, false}};
  for (const Case& c : cases) {
    const ColourBlob pinhole = blobOf(lookAtBall(levelCamera(), c.centre), "green");
    const ColourBlob raw = blobOf(lookAtBall(barrelCamera(), c.centre), "green");
    ASSERT_TRUE(pinhole.found && raw.found) << c.centre;
    EXPECT_GT(1.0 - raw.area / pinhole.area, c.raw_shrink_min) << c.centre;
    const RectifiedBlob rectified = rectifyBlob(raw, barrelCamera(), {kWidth, kHeight});
    EXPECT_NEAR(rectified.area_in_frame, pinhole.area, 0.005 * pinhole.area) << c.centre;
    if (c.cut) {
      EXPECT_GT(rectified.area, 1.01 * pinhole.area) << c.centre;
      continue;
    }
    EXPECT_NEAR(rectified.area, pinhole.area, 0.005 * pinhole.area) << c.centre;
    EXPECT_NEAR(rectified.centroid.x, pinhole.centroid.x, 0.3) << c.centre;
    EXPECT_NEAR(rectified.centroid.y, pinhole.centroid.y, 0.3) << c.centre;
    EXPECT_NEAR(rectified.circle_radius, pinhole.circle_radius, 1.0) << c.centre;
    EXPECT_NEAR(rectified.width, pinhole.bounding_box.width, 1.0) << c.centre;
  }
}

// ---- Controller: configuration -------------------------------------------------------------

TEST(BeaconControllerConfig, DefaultIsValidAndModesRoundTrip) {
  EXPECT_EQ(validate(BeaconControllerConfig()), "");
  for (BeaconMode mode : {BeaconMode::kFollowGreenStopRed, BeaconMode::kApproach}) {
    EXPECT_EQ(parseBeaconMode(toString(mode)), mode);
  }
  EXPECT_FALSE(parseBeaconMode("follow"));
  EXPECT_STREQ(toString(BeaconState::kStoppedByRed), "stopped_by_red");
  EXPECT_STREQ(toString(BeaconState::kArrived), "arrived");
}

TEST(BeaconControllerConfig, ValidateNamesTheBadField) {
  BeaconControllerConfig config;
  config.close_area = -1.0;
  EXPECT_EQ(validate(config), "close_area must be >= 0, got -1");
  config = BeaconControllerConfig();
  config.stop_min_area = -5.0;
  EXPECT_EQ(validate(config), "stop_min_area must be >= 0, got -5");
  config = BeaconControllerConfig();
  config.stop_colour = "green";
  EXPECT_EQ(validate(config), "follow_colour and stop_colour must differ, both are 'green'");
  config = BeaconControllerConfig();
  config.target_colour = "";
  EXPECT_EQ(validate(config), "target_colour must not be empty");
  config = BeaconControllerConfig();
  config.stop_distance = 0.0;
  EXPECT_EQ(validate(config), "stop_distance must be > 0, got 0");
  config = BeaconControllerConfig();
  config.target.size_m = kNaN;
  EXPECT_EQ(validate(config), "target.size_m must be > 0, got nan");
  config = BeaconControllerConfig();
  config.camera.fx = -1.0;
  EXPECT_EQ(validate(config), "camera.fx must be > 0, got -1");
  config = BeaconControllerConfig();
  config.search_rate = kNaN;
  EXPECT_EQ(validate(config), "search_rate must be >= 0, got nan");
  EXPECT_THROW(BeaconController{config}, std::invalid_argument);
}

TEST(BeaconControllerConfig, ColoursMustBeDetected) {
  BeaconControllerConfig controller;
  ColourBlobConfig detector;
  EXPECT_EQ(checkColoursDetected(controller, detector), "");
  detector.colours.erase(detector.colours.begin());  // no red
  EXPECT_EQ(checkColoursDetected(controller, detector),
            "stop_colour 'red' is not one of the detector's colours");
  controller.mode = BeaconMode::kApproach;
  EXPECT_EQ(checkColoursDetected(controller, detector), "");
  controller.target_colour = "yellow";
  EXPECT_EQ(checkColoursDetected(controller, detector),
            "target_colour 'yellow' is not one of the detector's colours");
}

// ---- Controller: follow green, stop on red -------------------------------------------------

BlobResult blobs(std::vector<ColourBlob> colours) {
  BlobResult result;
  result.image_width = kWidth;
  result.image_height = kHeight;
  result.colours = std::move(colours);
  return result;
}

ColourBlob blob(const std::string& name, double centroid_x, double area) {
  ColourBlob b;
  b.name = name;
  b.found = true;
  b.blob_count = 1;
  b.area = area;
  b.centroid = cv::Point2d(centroid_x, 240.0);
  const double radius = std::sqrt(area / kPi);
  b.circle_centre = cv::Point2f(centroid_x, 240.0f);
  b.circle_radius = static_cast<float>(radius);
  b.bounding_box = cv::Rect(cvRound(centroid_x - radius), cvRound(240 - radius),
                            cvRound(2 * radius) + 1, cvRound(2 * radius) + 1);
  return b;
}

ColourBlob absent(const std::string& name) {
  ColourBlob b;
  b.name = name;
  return b;
}

BlobResult nothing() { return blobs({absent("red"), absent("green"), absent("blue")}); }
BlobResult green(double x, double area) {
  return blobs({absent("red"), blob("green", x, area), absent("blue")});
}
BlobResult greenAndRed(double x, double area, double red_area) {
  return blobs({blob("red", 500.0, red_area), blob("green", x, area), absent("blue")});
}

TEST(FollowGreenStopRed, SpinsToSearchWithoutGreen) {
  BeaconController controller;
  const Twist2D twist = controller.update(nothing(), 0.0);
  EXPECT_EQ(controller.state(), BeaconState::kSearching);
  EXPECT_EQ(twist.linear, 0.0);
  EXPECT_EQ(twist.angular, controller.config().search_rate);  // left, having seen nothing yet
}

TEST(FollowGreenStopRed, TurnsTowardSmallGreenAndDrives) {
  BeaconController controller;
  Twist2D twist = controller.update(green(480.0, 2000.0), 0.0);  // right of centre, e = 0.5
  EXPECT_EQ(controller.state(), BeaconState::kApproaching);
  EXPECT_EQ(twist.linear, controller.config().approach_speed);
  EXPECT_DOUBLE_EQ(twist.angular, -controller.config().turn_gain * 0.5);
  twist = controller.update(green(160.0, 2000.0), 0.1);  // left
  EXPECT_DOUBLE_EQ(twist.angular, controller.config().turn_gain * 0.5);
  twist = controller.update(green(320.0, 2000.0), 0.2);  // centred
  EXPECT_EQ(twist.angular, 0.0);
}

TEST(FollowGreenStopRed, HoldsWhenGreenIsClose) {
  BeaconController controller;
  const double close = controller.config().close_area;
  Twist2D twist = controller.update(green(330.0, close), 0.0);
  EXPECT_EQ(controller.state(), BeaconState::kHolding);
  EXPECT_EQ(twist.linear, 0.0);
  EXPECT_EQ(twist.angular, 0.0);
  // A dip of the area within hold_release of the hold (exposure, noise) keeps it holding.
  const double release = close / std::pow(1.0 + controller.config().hold_release, 2);
  twist = controller.update(green(330.0, release + 1.0), 0.1);
  EXPECT_EQ(controller.state(), BeaconState::kHolding);
  EXPECT_EQ(twist.linear, 0.0);
  twist = controller.update(green(330.0, release - 1.0), 0.2);
  EXPECT_EQ(controller.state(), BeaconState::kApproaching);
  EXPECT_GT(twist.linear, 0.0);
  // From an approach, the hold starts at close_area itself.
  twist = controller.update(green(330.0, close - 1.0), 0.3);
  EXPECT_EQ(controller.state(), BeaconState::kApproaching);
}

TEST(FollowGreenStopRed, SlowsDownNearTheHoldToCreepSpeed) {
  BeaconController controller;
  const BeaconControllerConfig& config = controller.config();
  // Half the taper's distance left: half the speed.
  const double half_way = config.close_area / std::pow(1.0 + 0.5 * config.approach_taper, 2);
  EXPECT_NEAR(controller.update(green(320.0, half_way), 0.0).linear, 0.5 * config.approach_speed,
              1e-9);
  EXPECT_EQ(controller.update(green(320.0, config.close_area - 1.0), 0.1).linear,
            config.creep_speed);
  BeaconControllerConfig lecture = config;
  lecture.approach_taper = 0.0;
  EXPECT_EQ(BeaconController(lecture).update(green(320.0, config.close_area - 1.0), 0.0).linear,
            lecture.approach_speed);
}

// Where the follow mode holds in front of a 0.2 m ball straight ahead, from 3 m, when the base
// starts each command `delay` s late and reaches its speed with a first-order lag of time
// constant `lag` s (the harsh profile's 50-150 ms and 0.1-0.2 s). The ball's silhouette area
// at a distance d from the camera is pi f^2 r^2 / (d^2 - r^2), exactly, for a pinhole of focal
// length f = 554 px (the harness camera's). Returns the camera-to-centre distance at rest.
constexpr double kHarnessFocalPx = 554.3;
constexpr double kBallRadius = 0.2;
double ballArea(double distance) {
  return kPi * kHarnessFocalPx * kHarnessFocalPx * kBallRadius * kBallRadius /
         (distance * distance - kBallRadius * kBallRadius);
}

double holdDistance(const BeaconControllerConfig& config, double delay, double lag) {
  constexpr double kDt = 1.0 / 30.0;
  BeaconController controller(config);
  std::vector<double> in_flight(static_cast<size_t>(std::lround(delay / kDt)), 0.0);
  double distance = 3.0;
  double speed = 0.0;
  for (double t = 0.0; t < 40.0; t += kDt) {
    in_flight.push_back(controller.update(green(320.0, ballArea(distance)), t).linear);
    const double commanded = in_flight.front();
    in_flight.erase(in_flight.begin());
    speed += lag > 0.0 ? (commanded - speed) * (1.0 - std::exp(-kDt / lag)) : commanded - speed;
    distance -= speed * kDt;
  }
  return distance;
}

TEST(FollowGreenStopRed, HoldsWithinAFewMillimetresOfTheHoldDistanceOnALateSluggishBase) {
  const BeaconControllerConfig config;
  // ballArea(hold) == close_area.
  const double hold = std::sqrt(kPi * kHarnessFocalPx * kHarnessFocalPx * kBallRadius *
                                    kBallRadius / config.close_area +
                                kBallRadius * kBallRadius);
  EXPECT_NEAR(holdDistance(config, 0.0, 0.0), hold, 0.002);
  for (const auto& [delay, lag] : {std::pair{0.067, 0.1}, {0.1, 0.2}, {0.15, 0.2}}) {
    // Short of the hold by creep_speed x (delay + lag) at most, ~7 mm.
    const double overrun = hold - holdDistance(config, delay, lag);
    EXPECT_GE(overrun, -0.002) << delay << " s, " << lag << " s";
    EXPECT_LE(overrun, config.creep_speed * (delay + lag) + 0.002)
        << delay << " s, " << lag << " s";
  }
  // At full speed to the hold (the lecture's law) the same base overruns by 63 mm.
  BeaconControllerConfig lecture = config;
  lecture.approach_taper = 0.0;
  EXPECT_GT(hold - holdDistance(lecture, 0.1, 0.2), 0.04);
}

TEST(FollowGreenStopRed, SearchTurnsTowardWhereGreenWasLastSeen) {
  BeaconController controller;
  controller.update(green(600.0, 2000.0), 0.0);
  EXPECT_EQ(controller.update(nothing(), 0.1).angular, -controller.config().search_rate);
  controller.update(green(20.0, 2000.0), 0.2);
  EXPECT_EQ(controller.update(nothing(), 0.3).angular, controller.config().search_rate);
}

TEST(FollowGreenStopRed, RedStopsAtOnceStaysStoppedWhileVisibleThenResumes) {
  BeaconController controller;
  double t = 0.0;
  for (; t < 1.0; t += 0.1) controller.update(green(400.0, 2000.0), t);
  ASSERT_EQ(controller.state(), BeaconState::kApproaching);

  // Red appears: the very first frame gives zero.
  Twist2D twist = controller.update(greenAndRed(400.0, 2000.0, 800.0), t);
  EXPECT_EQ(controller.state(), BeaconState::kStoppedByRed);
  EXPECT_EQ(twist.linear, 0.0);
  EXPECT_EQ(twist.angular, 0.0);
  // ... and zero for as long as red stays in view, whatever green does.
  for (int i = 0; i < 50; ++i) {
    t += 0.1;
    const BlobResult frame = i % 2 ? greenAndRed(100.0, 2000.0, 800.0)
                                   : blobs({blob("red", 300.0, 800.0), absent("green")});
    twist = controller.update(frame, t);
    EXPECT_EQ(controller.state(), BeaconState::kStoppedByRed);
    EXPECT_EQ(twist.linear, 0.0);
    EXPECT_EQ(twist.angular, 0.0);
  }
  // Red gone: still stopped within the release delay, then following resumes.
  const double red_last_seen = t;
  t += 0.5 * controller.config().stop_release_delay;
  twist = controller.update(green(400.0, 2000.0), t);
  EXPECT_EQ(controller.state(), BeaconState::kStoppedByRed);
  EXPECT_EQ(twist.linear, 0.0);
  t = red_last_seen + controller.config().stop_release_delay + 0.05;
  twist = controller.update(green(400.0, 2000.0), t);
  EXPECT_EQ(controller.state(), BeaconState::kApproaching);
  EXPECT_EQ(twist.linear, controller.config().approach_speed);
  EXPECT_LT(twist.angular, 0.0);
}

TEST(FollowGreenStopRed, RedStopsEvenWhileSearchingOrHolding) {
  BeaconController controller;
  controller.update(nothing(), 0.0);
  EXPECT_EQ(controller.update(blobs({blob("red", 300.0, 800.0)}), 0.1).angular, 0.0);
  EXPECT_EQ(controller.state(), BeaconState::kStoppedByRed);
}

TEST(FollowGreenStopRed, SmallRedIsIgnored) {
  BeaconController controller;
  const double small = controller.config().stop_min_area - 1.0;
  const Twist2D twist = controller.update(greenAndRed(320.0, 2000.0, small), 0.0);
  EXPECT_EQ(controller.state(), BeaconState::kApproaching);
  EXPECT_GT(twist.linear, 0.0);
}

TEST(FollowGreenStopRed, RejectedFramesAndBadStampsGiveZeroAndKeepTheState) {
  BeaconController controller;
  controller.update(green(400.0, 2000.0), 0.0);
  BlobResult rejected = green(400.0, 2000.0);
  rejected.error = "empty frame";
  Twist2D twist = controller.update(rejected, 0.1);
  EXPECT_EQ(twist.linear, 0.0);
  EXPECT_EQ(twist.angular, 0.0);
  EXPECT_EQ(controller.state(), BeaconState::kApproaching);
  twist = controller.update(green(400.0, 2000.0), kNaN);
  EXPECT_EQ(twist.linear, 0.0);
  EXPECT_EQ(controller.state(), BeaconState::kApproaching);
}

TEST(FollowGreenStopRed, StampGoingBackwardsResets) {
  BeaconController controller;
  controller.update(greenAndRed(400.0, 2000.0, 800.0), 10.0);
  ASSERT_EQ(controller.state(), BeaconState::kStoppedByRed);
  // A restarted clock: the red memory from t = 10 must not hold the robot.
  const Twist2D twist = controller.update(green(400.0, 2000.0), 0.0);
  EXPECT_EQ(controller.state(), BeaconState::kApproaching);
  EXPECT_GT(twist.linear, 0.0);
}

TEST(FollowGreenStopRed, NeverNaN) {
  BeaconController controller;
  BlobResult frame = green(kNaN, 2000.0);
  Twist2D twist = controller.update(frame, 0.0);
  EXPECT_TRUE(std::isfinite(twist.linear) && std::isfinite(twist.angular));
  frame = green(400.0, kNaN);
  twist = controller.update(frame, 0.1);
  EXPECT_TRUE(std::isfinite(twist.linear) && std::isfinite(twist.angular));
}

// ---- Controller: approach ------------------------------------------------------------------

BeaconControllerConfig approachConfig() {
  BeaconControllerConfig config;
  config.mode = BeaconMode::kApproach;
  config.target_colour = "green";
  config.target = BeaconObject{BeaconShape::kBox, 1.8};
  config.camera = levelCamera();
  return config;
}

TEST(FollowGreenStopRed, HoldsAndSteersOnRawFramesThroughTheLensAsOnRectifiedOnes) {
  BeaconControllerConfig config;
  config.camera = barrelCamera();
  BeaconController through_lens(config);
  config.camera.lens.reset();
  BeaconController pinhole(config);
  // Off the axis and beyond the hold point: the same turn as on the pinhole frame, where the
  // raw centroid turns less.
  const cv::Point3d far(1.2, -0.3, 0.2);
  const Twist2D expected = pinhole.update(lookAtBall(levelCamera(), far), 0.0);
  ASSERT_EQ(pinhole.state(), BeaconState::kApproaching);
  const BlobResult raw_far = lookAtBall(barrelCamera(), far);
  const Twist2D twist = through_lens.update(raw_far, 0.0);
  EXPECT_EQ(through_lens.state(), BeaconState::kApproaching);
  EXPECT_EQ(twist.linear, expected.linear);
  EXPECT_NEAR(twist.angular, expected.angular, 0.001 * std::abs(expected.angular));
  pinhole.reset();
  EXPECT_GT(std::abs(pinhole.update(raw_far, 0.0).angular - expected.angular),
            0.005 * std::abs(expected.angular))
      << "the lens must matter for this test to mean anything";
  // 0.485 m from the ball's surface (beyond where the pinhole first holds): holding on both
  // frames; the raw blob's own area (2 % short of close_area) would have driven on.
  const cv::Point3d near(0.685, 0.0, 0.2);
  pinhole.reset();
  pinhole.update(lookAtBall(levelCamera(), near), 1.0);
  EXPECT_EQ(pinhole.state(), BeaconState::kHolding);
  const BlobResult raw_near = lookAtBall(barrelCamera(), near);
  const Twist2D hold = through_lens.update(raw_near, 1.0);
  EXPECT_EQ(hold.linear, 0.0);
  EXPECT_EQ(hold.angular, 0.0);
  EXPECT_EQ(through_lens.state(), BeaconState::kHolding);
  pinhole.reset();
  pinhole.update(raw_near, 1.0);
  EXPECT_EQ(pinhole.state(), BeaconState::kApproaching);
}

// The box, and optionally another of its colour further away (drawn first, so the box hides it).
BlobResult look(const ColourBlobDetector& detector, const CameraGeometry& camera, const Pose& robot,
                const Box& box, const std::optional<Box>& farther = std::nullopt) {
  cv::Mat frame = emptyScene(camera);
  if (farther) drawBox(frame, camera, robot, *farther, kDumpsterGreen);
  drawBox(frame, camera, robot, box, kDumpsterGreen);
  return detector.detect(frame);
}

TEST(Approach, SearchesDrivesSlowsAndArrives) {
  const ColourBlobDetector detector(boxTargetDetector());
  const BeaconControllerConfig config = approachConfig();
  BeaconController controller(config);
  Twist2D twist = controller.update(detector.detect(emptyScene(config.camera)), 0.0);
  EXPECT_EQ(controller.state(), BeaconState::kSearching);
  EXPECT_EQ(twist.angular, config.search_rate);
  EXPECT_FALSE(controller.lastRange());

  twist = controller.update(look(detector, config.camera, Pose(), dumpsterAt(4.0)), 0.1);
  EXPECT_EQ(controller.state(), BeaconState::kApproaching);
  EXPECT_NEAR(twist.linear, config.max_linear, 1e-6);
  EXPECT_NEAR(twist.angular, 0.0, 1e-3);
  ASSERT_TRUE(controller.lastRange());
  EXPECT_NEAR(*controller.lastRange(), 4.0, groundRangeTolerance(config.camera, 4.0));

  twist = controller.update(look(detector, config.camera, Pose(), dumpsterAt(1.2)), 0.2);
  EXPECT_NEAR(twist.linear, config.k_range * 0.2, 0.005) << "proportional near the goal";

  // The object off to the right: turn right, and drive slower the further off it is.
  twist = controller.update(look(detector, config.camera, Pose(), dumpsterAt(3.0, -1.0)), 0.3);
  EXPECT_LT(twist.angular, 0.0);
  EXPECT_LT(twist.linear, config.max_linear);
  ASSERT_TRUE(controller.lastBearing());
  EXPECT_GT(*controller.lastBearing(), 0.0) << "right of the axis is a positive bearing";

  // The face fills the view: no bearing seen, so the last one less the turn commanded since
  // (and the parallax of the few mm driven, 7e-5 rad).
  const double seen = *controller.lastBearing();
  const double turn = twist.angular;
  twist = controller.update(look(detector, config.camera, Pose(), dumpsterAt(1.0)), 0.4);
  EXPECT_EQ(controller.state(), BeaconState::kApproaching);
  ASSERT_TRUE(controller.lastBearing());
  EXPECT_NEAR(*controller.lastBearing(), seen + turn * 0.1, 2e-4);
  EXPECT_LT(twist.angular, 0.0) << "still turning right";

  controller.update(look(detector, config.camera, Pose(), dumpsterAt(2.0)), 0.5);  // seen ahead
  twist = controller.update(look(detector, config.camera, Pose(), dumpsterAt(1.0)), 0.6);
  EXPECT_EQ(controller.state(), BeaconState::kArrived);
  EXPECT_EQ(twist.linear, 0.0);
  EXPECT_EQ(twist.angular, 0.0);

  twist = controller.update(look(detector, config.camera, Pose(), dumpsterAt(0.8)), 0.7);
  EXPECT_EQ(twist.linear, 0.0) << "too close: never reverses by default";
}

TEST(Approach, StaysArrivedThroughRangeJitterWithinTheReleaseBounds) {
  const ColourBlobDetector detector(boxTargetDetector());
  const BeaconControllerConfig config = approachConfig();
  BeaconController controller(config);
  controller.update(look(detector, config.camera, Pose(), dumpsterAt(1.0)), 0.0);
  ASSERT_EQ(controller.state(), BeaconState::kArrived);
  // A range 10 mm long (a row or two of jitter) is outside the arrival tolerance but inside the
  // release bound: still arrived, no creep.
  const double jittered = 1.0 + 0.5 * (config.distance_tolerance + config.distance_release);
  Twist2D twist =
      controller.update(look(detector, config.camera, Pose(), dumpsterAt(jittered)), 0.1);
  EXPECT_EQ(controller.state(), BeaconState::kArrived);
  EXPECT_EQ(twist.linear, 0.0);
  // Moved away beyond the release bound: approach again.
  twist = controller.update(look(detector, config.camera, Pose(), dumpsterAt(1.05)), 0.2);
  EXPECT_EQ(controller.state(), BeaconState::kApproaching);
  EXPECT_GT(twist.linear, 0.0);
  // Back at the same jittered range, not arrived before: the arrival tolerance applies.
  controller.update(look(detector, config.camera, Pose(), dumpsterAt(jittered)), 0.3);
  EXPECT_EQ(controller.state(), BeaconState::kApproaching);
}

TEST(Approach, ReversesOnlyWhenAllowed) {
  const ColourBlobDetector detector(boxTargetDetector());
  BeaconControllerConfig config = approachConfig();
  config.allow_reverse = true;
  BeaconController controller(config);
  const Twist2D twist =
      controller.update(look(detector, config.camera, Pose(), dumpsterAt(0.8)), 0.0);
  EXPECT_NEAR(twist.linear, -config.k_range * 0.2, 0.005);
}

TEST(Approach, HoldsStillWhenTheTargetIsLostThenSearches) {
  const ColourBlobDetector detector(boxTargetDetector());
  const BeaconControllerConfig config = approachConfig();
  BeaconController controller(config);
  // Seen on the right, then gone.
  controller.update(look(detector, config.camera, Pose(), dumpsterAt(3.0, -1.0)), 0.0);
  ASSERT_EQ(controller.state(), BeaconState::kApproaching);
  const BlobResult empty = detector.detect(emptyScene(config.camera));
  Twist2D twist = controller.update(empty, 0.1);
  EXPECT_EQ(controller.state(), BeaconState::kLost);
  EXPECT_EQ(twist.linear, 0.0);
  EXPECT_EQ(twist.angular, 0.0);
  twist = controller.update(empty, config.lost_hold);
  EXPECT_EQ(controller.state(), BeaconState::kLost);
  twist = controller.update(empty, config.lost_hold + 0.1);
  EXPECT_EQ(controller.state(), BeaconState::kSearching);
  EXPECT_EQ(twist.angular, -config.search_rate) << "toward the right, where it was last seen";
}

TEST(Approach, WithoutARangeOnlyTurns) {
  const ColourBlobDetector detector;
  BeaconControllerConfig config = approachConfig();
  config.target = BeaconObject{BeaconShape::kSphere, 0.2};
  BeaconController controller(config);
  cv::Mat frame = emptyScene(config.camera);
  drawSphere(frame, config.camera, Pose(), {{2.0, 1.15, 0.2}, 0.2}, cv::Scalar(0, 200, 0));
  const Twist2D twist = controller.update(detector.detect(frame), 0.0);  // cut by the edge
  EXPECT_EQ(controller.state(), BeaconState::kApproaching);
  EXPECT_FALSE(controller.lastRange());
  EXPECT_EQ(twist.linear, 0.0);
  EXPECT_GT(twist.angular, 0.0);
}

// Integrates a unicycle exactly over dt.
void drive(Pose& robot, const Twist2D& twist, double dt) {
  const double v = twist.linear;
  const double w = twist.angular;
  if (std::abs(w) < 1e-9) {
    robot.x += v * std::cos(robot.yaw) * dt;
    robot.y += v * std::sin(robot.yaw) * dt;
  } else {
    const double yaw = robot.yaw + w * dt;
    robot.x += v / w * (std::sin(yaw) - std::sin(robot.yaw));
    robot.y -= v / w * (std::cos(yaw) - std::cos(robot.yaw));
    robot.yaw = yaw;
  }
}

struct Outcome {
  double distance = 0.0;     // base centre to the footprint, m
  double bearing_deg = 0.0;  // heading to the box centre, deg
  bool arrived = false;
  double time = 0.0;
};

// A base that applies each command `delay` s late, through a first-order motor lag of time
// constant `lag` s, as the harness's harsh profile draws them (50-150 ms, 0.1-0.2 s).
struct SluggishBase {
  double delay = 0.0;
  double lag = 0.0;
};

// The closed loop of Exercise 10 at the harness camera's 30 Hz: render, detect, control,
// limit, move. Ends a second after the controller first reports kArrived.
Outcome approachInClosedLoop(const Pose& start, const Box& box, const SluggishBase& base = {},
                             const std::optional<Box>& farther = std::nullopt) {
  ColourBlobConfig green_only = boxTargetDetector();  // as an approach node configures it
  green_only.colours = {*parseColourName("green")};
  const ColourBlobDetector detector(green_only);
  const BeaconControllerConfig config = approachConfig();
  BeaconController controller(config);
  VelocityLimiter limiter;
  constexpr double kDt = 1.0 / 30.0;
  Pose robot = start;
  Outcome outcome;
  double arrived_at = -1.0;
  std::vector<Twist2D> in_flight(static_cast<size_t>(std::lround(base.delay / kDt)));
  Twist2D motion;
  const double follow = base.lag > 0.0 ? 1.0 - std::exp(-kDt / base.lag) : 1.0;
  for (double t = 0.0; t < 60.0; t += kDt) {
    in_flight.push_back(limiter.limit(
        controller.update(look(detector, config.camera, robot, box, farther), t), kDt));
    const Twist2D command = in_flight.front();
    in_flight.erase(in_flight.begin());
    motion.linear += follow * (command.linear - motion.linear);
    motion.angular += follow * (command.angular - motion.angular);
    drive(robot, motion, kDt);
    if (controller.state() == BeaconState::kArrived && arrived_at < 0.0) arrived_at = t;
    if (arrived_at >= 0.0 && t > arrived_at + 1.0) break;
    outcome.time = t;
  }
  outcome.arrived = arrived_at >= 0.0;
  outcome.distance = distanceToFootprint(robot, box);
  outcome.bearing_deg = bearingToCentreDeg(robot, box.x, box.y);
  return outcome;
}

TEST(Approach, ClosedLoopStopsOneMetreFromABoxFacingIt) {
  for (double gap : {2.0, 4.0, 6.0}) {
    for (double heading_deg : {-30.0, 30.0}) {
      const Outcome outcome =
          approachInClosedLoop(Pose{0.0, 0.0, degrees(heading_deg)}, dumpsterAt(gap));
      EXPECT_TRUE(outcome.arrived) << gap << " m, " << heading_deg << " deg";
      EXPECT_NEAR(outcome.distance, 1.0, 0.01) << gap << " m, " << heading_deg << " deg";
      EXPECT_LT(outcome.bearing_deg, 1.0) << gap << " m, " << heading_deg << " deg";
    }
  }
}

TEST(Approach, ClosedLoopPastAnotherObjectOfTheColourEndsFacingTheBox) {
  // A green box 3 m behind the dumpster's face and 2.5 m to its right: approaching along the
  // axis, the robot sees it join the dumpster's silhouette on the right from about 2 m from the
  // face until the face fills the view. The silhouette's middle then lay right of the
  // dumpster's and the robot came to rest turned toward it, 0.9-1.0 deg off from 4 m (the harsh
  // dumpster sweep's member 037 and a green band on the wall: 3.7 deg). On bases 100 and 150
  // ms late with a 0.2 s motor lag, the harsh profile's slowest.
  for (const SluggishBase& base : {SluggishBase{0.1, 0.2}, SluggishBase{0.15, 0.2}}) {
    for (double gap : {2.0, 4.0}) {
      for (double heading_deg : {-30.0, 30.0}) {
        const Box dumpster = dumpsterAt(gap);
        const Box behind{dumpster.x + 0.5 + 3.0, -2.5, 0.0, 0.8, 0.8, 0.9};
        const Outcome outcome =
            approachInClosedLoop(Pose{0.0, 0.0, degrees(heading_deg)}, dumpster, base, behind);
        const std::string where = std::to_string(gap) + " m, " + std::to_string(heading_deg) +
                                  " deg, " + std::to_string(base.delay) + " s late";
        EXPECT_TRUE(outcome.arrived) << where;
        EXPECT_NEAR(outcome.distance, 1.0, 0.015) << where;
        EXPECT_LT(outcome.bearing_deg, 0.3) << where;
      }
    }
  }
}

TEST(Approach, ClosedLoopFromAnOffAxisStart) {
  // The box 30 deg off the robot's heading and the robot off the box's axis: it turns, drives
  // to the face and still ends 1 m from the footprint, facing the box.
  for (double gap : {2.0, 4.0, 6.0}) {
    for (double side : {-1.0, 1.0}) {
      const double lateral = side * (gap + 0.5) * std::tan(degrees(30.0));
      const Outcome outcome = approachInClosedLoop(Pose(), dumpsterAt(gap, lateral));
      EXPECT_TRUE(outcome.arrived) << gap << " m, side " << side;
      EXPECT_NEAR(outcome.distance, 1.0, 0.01) << gap << " m, side " << side;
      EXPECT_LT(outcome.bearing_deg, 1.0) << gap << " m, side " << side;
    }
  }
}

}  // namespace
}  // namespace follow_bot
