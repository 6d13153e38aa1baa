// follow_bot.core: the ROS-free C++ cores from Python, with no logic of their own. The
// conventions (frames, configs, results) are follow_bot_common/pybind_support.h's; the detectors'
// and controllers' constructors run the same validate() as the configs.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot/beacon_controller.h"
#include "follow_bot/colour_blobs.h"
#include "follow_bot/common.h"
#include "follow_bot/line_controller.h"
#include "follow_bot/line_detector.h"
#include "follow_bot/line_path.h"
#include "follow_bot/marker_target.h"
#include "follow_bot/parking_servo.h"
#include "follow_bot/sign_detector.h"
#include "follow_bot/steering_law.h"
#include "follow_bot/tag_detector.h"
#include "follow_bot_common/CameraDefaults.h"
#include "follow_bot_common/camera_mounting.h"
#include "follow_bot_common/frame_watchdog.h"
#include "follow_bot_common/ground_projection.h"
#include "follow_bot_common/pybind_support.h"
#include "follow_bot_common/velocity_limiter.h"

namespace py = pybind11;
using namespace py::literals;

namespace follow_bot {
namespace {

using namespace pybind_support;

// A read-only 2-D view of `array`, which must be rows x cols (ValueError naming `name` otherwise).
py::detail::unchecked_reference<double, 2> fixedShape(const py::array_t<double>& array, int rows,
                                                      int cols, const char* name) {
  if (array.ndim() != 2 || array.shape(0) != rows || array.shape(1) != cols) {
    throw py::value_error(std::string(name) + " must be " + std::to_string(rows) + "x" +
                          std::to_string(cols) + ", got shape " + shapeOf(array));
  }
  return array.unchecked<2>();
}

// ---- bindings --------------------------------------------------------------------------------

void bindVelocity(py::module_& m) {
  py::class_<Twist2D> twist(m, "Twist2D",
                            "A planar command (REP-103): linear m/s forward, angular rad/s, "
                            "positive = turning left.");
  twist.def_readwrite("linear", &Twist2D::linear).def_readwrite("angular", &Twist2D::angular);
  defKeywordInit(twist);

  py::class_<VelocityLimiterConfig> config(m, "VelocityLimiterConfig");
  config.def_readwrite("max_linear", &VelocityLimiterConfig::max_linear)
      .def_readwrite("max_angular", &VelocityLimiterConfig::max_angular)
      .def_readwrite("max_linear_accel", &VelocityLimiterConfig::max_linear_accel)
      .def_readwrite("max_angular_accel", &VelocityLimiterConfig::max_angular_accel)
      .def_readwrite("allow_reverse", &VelocityLimiterConfig::allow_reverse);
  defKeywordInit(config,
                 static_cast<Validator<VelocityLimiterConfig>>(&follow_bot_common::validate));

  py::class_<VelocityLimiter>(m, "VelocityLimiter",
                              "Clamps and rate-limits velocity commands; never passes a NaN.")
      .def(py::init<const VelocityLimiterConfig&>(), "config"_a = VelocityLimiterConfig())
      .def("limit", &VelocityLimiter::limit, "desired"_a, "dt"_a,
           "The command to send, given the desired one and the seconds since the last call.")
      .def("stop", &VelocityLimiter::stop, "Immediate zero; the next limit() ramps up from rest.")
      .def("reset", &VelocityLimiter::reset, "Forgets the previous output (robot at rest).")
      .def_property_readonly("last_output", [](const VelocityLimiter& l) { return l.lastOutput(); })
      .def_property_readonly(
          "config", [](const VelocityLimiter& l) { return l.config(); }, "A copy of the config.");
}

void bindWatchdog(py::module_& m) {
  py::class_<FrameWatchdog>(m, "FrameWatchdog",
                            "Tracks frame arrival times (seconds, one clock) to detect a stalled "
                            "camera; the timeout follows the camera's measured rate "
                            "(3 frame intervals), never below timeout_s.")
      .def(py::init<double, double>(), "timeout_s"_a, "expected_period_s"_a = 0.0)
      .def("frame_arrived", &FrameWatchdog::frameArrived, "t"_a)
      .def("alive_at", &FrameWatchdog::aliveAt, "t"_a)
      .def("expired", &FrameWatchdog::expired, "now"_a)
      .def("should_send_stop", &FrameWatchdog::shouldSendStop, "now"_a,
           "True exactly once per outage.")
      .def("reset", &FrameWatchdog::reset)
      .def_property_readonly("timeout", &FrameWatchdog::timeout)
      .def_property_readonly("min_timeout", &FrameWatchdog::minTimeout)
      .def_property_readonly("frame_interval", &FrameWatchdog::frameInterval)
      .def_property_readonly("last_frame", &FrameWatchdog::lastFrame);
  // CommandOutput's ~watchdog_timeout default (follow_bot_common/cfg/CommandOutput.cfg), s.
  m.attr("WATCHDOG_TIMEOUT") = follow_bot_common::CommandOutputDefaults::watchdog_timeout;
  // Its ~expected_frame_rate default, Hz (0: unknown).
  m.attr("EXPECTED_FRAME_RATE") = follow_bot_common::CommandOutputDefaults::expected_frame_rate;
}

void bindLineDetector(py::module_& m) {
  py::class_<HsvColor> hsv(m, "HsvColor", "OpenCV 8-bit HSV: h 0..179 (degrees / 2), s, v 0..255.");
  hsv.def(py::init([](int h, int s, int v) {
            return HsvColor{h, s, v};
          }),
          "h"_a, "s"_a, "v"_a)
      .def_readwrite("h", &HsvColor::h)
      .def_readwrite("s", &HsvColor::s)
      .def_readwrite("v", &HsvColor::v);
  defKeywordInit(hsv);

  py::class_<BandConfig> band(m, "BandConfig",
                              "`rows` rows of the frame centred on the floor `distance_m` ahead "
                              "of base_link (see place_band).");
  band.def_readwrite("distance_m", &BandConfig::distance_m)
      .def_readwrite("rows", &BandConfig::rows);
  defKeywordInit(band);

  py::class_<BandPlacement> placement(m, "BandPlacement");
  placement.def_readwrite("row_begin", &BandPlacement::row_begin)
      .def_readwrite("row_end", &BandPlacement::row_end)
      .def_readwrite("distance_m", &BandPlacement::distance_m)
      .def_readwrite("clamped", &BandPlacement::clamped);
  m.def("ground_to_row", &groundToRow, "camera"_a, "distance_m"_a,
        "The image row of the floor distance_m ahead of base_link (centre column), or None.");
  m.def("place_band", &placeBand, "camera"_a, "band"_a, "image_height"_a,
        "The band's rows for this camera, clamped into the floor it sees.");

  py::class_<LineDetectorConfig> config(m, "LineDetectorConfig");
  config.def_readwrite("lower", &LineDetectorConfig::lower)
      .def_readwrite("upper", &LineDetectorConfig::upper)
      .def_readwrite("band", &LineDetectorConfig::band)
      .def_readwrite("look_ahead", &LineDetectorConfig::look_ahead);
  bindFields(config);
  defKeywordInit(config, static_cast<Validator<LineDetectorConfig>>(&validate));

  using RowSpan = BandMeasurement::RowSpan;
  py::class_<RowSpan> span(m, "RowSpan", "One band row's whole runs: their outer edges (columns).");
  span.def_readwrite("row", &RowSpan::row)
      .def_readwrite("left", &RowSpan::left)
      .def_readwrite("right", &RowSpan::right);
  defKeywordInit(span);

  py::class_<BandMeasurement> measurement(m, "BandMeasurement");
  measurement.def_readwrite("min_yellowness", &BandMeasurement::min_yellowness)
      .def_readwrite("block_min_yellowness", &BandMeasurement::block_min_yellowness)
      .def_readwrite("found", &BandMeasurement::found)
      .def_readwrite("pixel_count", &BandMeasurement::pixel_count)
      .def_readwrite("centroid_x", &BandMeasurement::centroid_x)
      .def_readwrite("centroid_y", &BandMeasurement::centroid_y)
      .def_readwrite("error_px", &BandMeasurement::error_px)
      .def_readwrite("error_normalised", &BandMeasurement::error_normalised)
      .def_readwrite("confidence", &BandMeasurement::confidence)
      .def_readwrite("centre_pixel_count", &BandMeasurement::centre_pixel_count)
      .def_readwrite("centre_found", &BandMeasurement::centre_found)
      .def_readwrite("centre_x", &BandMeasurement::centre_x)
      .def_readwrite("centre_y", &BandMeasurement::centre_y)
      .def_readwrite("spans", &BandMeasurement::spans)
      .def_readwrite("row_begin", &BandMeasurement::row_begin)
      .def_readwrite("row_end", &BandMeasurement::row_end)
      .def_readwrite("distance_m", &BandMeasurement::distance_m)
      .def_readwrite("clamped", &BandMeasurement::clamped);
  defKeywordInit(measurement);

  m.def(
      "floor_centre",
      [](const BandMeasurement& band, const CameraGeometry& camera) -> std::optional<py::tuple> {
        const std::optional<cv::Point2d> centre = floorCentre(band, camera);
        if (!centre) return std::nullopt;
        return pointTuple(*centre);
      },
      "band"_a, "camera"_a,
      "The line's centre on the floor (x forward, y left, m) from the band's row spans, or "
      "None.");

  py::class_<LineMeasurement> line(m, "LineMeasurement");
  line.def_readwrite("error", &LineMeasurement::error)
      .def_readwrite("image_width", &LineMeasurement::image_width)
      .def_readwrite("image_height", &LineMeasurement::image_height)
      .def_readwrite("band", &LineMeasurement::band)
      .def_readwrite("look_ahead", &LineMeasurement::look_ahead)
      .def_property_readonly("ok", &LineMeasurement::ok);
  defKeywordInit(line);

  py::class_<LineDetector>(m, "LineDetector",
                           "The follower's floor-line detector: the lecture's HSV band centroid.")
      .def(py::init<const LineDetectorConfig&, const CameraGeometry&>(),
           "config"_a = LineDetectorConfig(), "camera"_a = CameraGeometry())
      .def(
          "detect",
          [](const LineDetector& detector, const py::handle& bgr,
             const std::optional<LineMeasurement>& previous) {
            const cv::Mat frame = matView(bgr, 3);
            py::gil_scoped_release unlocked;
            return previous ? detector.detect(frame, *previous) : detector.detect(frame);
          },
          "bgr"_a, "previous"_a = py::none(),
          "The line in an HxWx3 uint8 BGR frame; with `previous` (the last measurement), only "
          "the band's blob nearest its sighting.")
      .def(
          "debug_mask",
          [](const LineDetector& detector, const py::handle& bgr) {
            return toArray(detector.debugMask(matView(bgr, 3)));
          },
          "bgr"_a, "HxW uint8: 255 on line pixels inside the band(s).")
      .def(
          "draw_debug",
          [](const LineDetector& detector, const py::handle& bgr,
             const LineMeasurement& measurement) {
            cv::Mat frame = matView(bgr, 3, true);
            return detector.drawDebug(frame, measurement);
          },
          "bgr"_a, "measurement"_a,
          "Draws the line pixels, bands and centroid onto the frame array, in place.")
      .def_property_readonly(
          "config", [](const LineDetector& d) { return d.config(); }, "A copy of the config.");
}

void bindColourBlobs(py::module_& m) {
  py::class_<ColourSpec> spec(
      m, "ColourSpec", "A hue window (centre +- sensitivity, wrapping) with S and V floors.");
  spec.def_readwrite("name", &ColourSpec::name)
      .def_readwrite("hue_centre", &ColourSpec::hue_centre)
      .def_readwrite("sensitivity", &ColourSpec::sensitivity)
      .def_readwrite("s_min", &ColourSpec::s_min)
      .def_readwrite("v_min", &ColourSpec::v_min)
      .def_readwrite("median_hue_min", &ColourSpec::median_hue_min)
      .def_readwrite("hue_offset_max", &ColourSpec::hue_offset_max)
      .def_readwrite("median_hue_max", &ColourSpec::median_hue_max);
  defKeywordInit(spec);
  m.def("parse_colour_name", &parseColourName, "name"_a,
        "The default ColourSpec of 'red', 'green' or 'blue'; None for other names.");

  py::class_<ColourBlobConfig> config(m, "ColourBlobConfig");
  config
      .def_readwrite("colours", &ColourBlobConfig::colours,
                     "A list (assign a new one to change it).")
      .def_readwrite("floor_ball", &ColourBlobConfig::floor_ball, "A FloorBall or None.");
  bindFields(config);
  defKeywordInit(config, static_cast<Validator<ColourBlobConfig>>(&validate));
  py::class_<ColourBlobConfig::FloorBall> floor_ball(config, "FloorBall");
  floor_ball.def_readwrite("radius_m", &ColourBlobConfig::FloorBall::radius_m)
      .def_readwrite("tolerance", &ColourBlobConfig::FloorBall::tolerance)
      .def_readwrite("camera", &ColourBlobConfig::FloorBall::camera);
  defKeywordInit(floor_ball);
  m.def("floor_ball_radius", &floorBallRadius, "camera"_a, "centre"_a, "radius_px"_a,
        "The radius of the ball on the floor whose silhouette is this circle; None if none fits.");

  py::class_<ColourBlob> blob(m, "ColourBlob",
                              "The chosen blob of one colour; pixel centres at integers.");
  blob.def_readwrite("name", &ColourBlob::name)
      .def_readwrite("found", &ColourBlob::found)
      .def_readwrite("blob_count", &ColourBlob::blob_count)
      .def_readwrite("area", &ColourBlob::area)
      .def_property(
          "centroid", [](const ColourBlob& b) { return pointTuple(b.centroid); },
          [](ColourBlob& b, const std::pair<double, double>& xy) { b.centroid = pointFrom(xy); },
          "(x, y) px")
      .def_property(
          "circle_centre",
          [](const ColourBlob& b) { return py::make_tuple(b.circle_centre.x, b.circle_centre.y); },
          [](ColourBlob& b, const std::pair<float, float>& xy) {
            b.circle_centre = {xy.first, xy.second};
          },
          "(x, y) px")
      .def_readwrite("circle_radius", &ColourBlob::circle_radius)
      .def_property(
          "bounding_box",
          [](const ColourBlob& b) {
            const cv::Rect& r = b.bounding_box;
            return py::make_tuple(r.x, r.y, r.width, r.height);
          },
          [](ColourBlob& b, const std::tuple<int, int, int, int>& r) {
            b.bounding_box = {std::get<0>(r), std::get<1>(r), std::get<2>(r), std::get<3>(r)};
          },
          "(x, y, width, height), inclusive pixels")
      .def_property(
          "contour",
          [](const ColourBlob& b) {
            py::array_t<int> out({static_cast<py::ssize_t>(b.contour.size()), py::ssize_t{2}});
            for (size_t i = 0; i < b.contour.size(); ++i) {
              *out.mutable_data(i, 0) = b.contour[i].x;
              *out.mutable_data(i, 1) = b.contour[i].y;
            }
            return out;
          },
          [](ColourBlob& b, const std::vector<std::pair<int, int>>& points) {
            b.contour.clear();
            for (const auto& [x, y] : points) b.contour.emplace_back(x, y);
          },
          "Nx2 int32 array of (x, y), every boundary pixel")
      .def_property_readonly(
          "circles",
          [](const ColourBlob& b) {
            py::array_t<float> out({static_cast<py::ssize_t>(b.circles.size()), py::ssize_t{3}});
            for (size_t i = 0; i < b.circles.size(); ++i) {
              for (int k = 0; k < 3; ++k) *out.mutable_data(i, k) = b.circles[i][k];
            }
            return out;
          },
          "Nx3 float32 array of (x, y, radius): every counted blob's circle, the chosen one's "
          "first");
  defKeywordInit(blob);

  py::class_<BlobResult> result(m, "BlobResult");
  result.def_readwrite("error", &BlobResult::error)
      .def_readwrite("image_width", &BlobResult::image_width)
      .def_readwrite("image_height", &BlobResult::image_height)
      .def_readwrite("colours", &BlobResult::colours, "One ColourBlob per configured colour.")
      .def_property_readonly("ok", &BlobResult::ok)
      .def(
          "find",
          [](const BlobResult& r, const std::string& name) -> std::optional<ColourBlob> {
            const ColourBlob* found = r.find(name);
            if (found == nullptr) return std::nullopt;
            return *found;
          },
          "name"_a, "The blob of the named colour, or None when that colour is not configured.");
  defKeywordInit(result);

  py::class_<ColourBlobDetector>(m, "ColourBlobDetector",
                                 "The largest blob of each configured colour (Lab 5).")
      .def(py::init<const ColourBlobConfig&>(), "config"_a = ColourBlobConfig())
      .def(
          "detect",
          [](const ColourBlobDetector& detector, const py::handle& bgr) {
            const cv::Mat frame = matView(bgr, 3);
            py::gil_scoped_release unlocked;
            return detector.detect(frame);
          },
          "bgr"_a, "Every configured colour in an HxWx3 uint8 BGR frame.")
      .def(
          "mask",
          [](const ColourBlobDetector& detector, const py::handle& bgr, const std::string& name) {
            return toArray(detector.mask(matView(bgr, 3), name));
          },
          "bgr"_a, "name"_a, "HxW uint8: the cleaned-up mask the named colour's blobs are in.")
      .def_property_readonly(
          "config", [](const ColourBlobDetector& d) { return d.config(); },
          "A copy of the config.");
}

void bindGeometry(py::module_& m) {
  py::class_<CameraGeometry> camera(m, "CameraGeometry",
                                    "Pinhole intrinsics (px) and mounting (m, rad) of the camera.");
  camera.def_readwrite("fx", &CameraGeometry::fx)
      .def_readwrite("fy", &CameraGeometry::fy)
      .def_readwrite("cx", &CameraGeometry::cx)
      .def_readwrite("cy", &CameraGeometry::cy)
      .def_readwrite("height_m", &CameraGeometry::height_m)
      .def_readwrite("pitch_rad", &CameraGeometry::pitch_rad)
      .def_readwrite("x_offset_m", &CameraGeometry::x_offset_m);
  defKeywordInit(camera, static_cast<Validator<CameraGeometry>>(&follow_bot_common::validate));

  m.def(
      "mounting_from_transform",
      [](const std::array<double, 3>& origin, const std::array<double, 4>& quaternion,
         double base_height_m, CameraGeometry camera) {
        std::string warning;
        const std::string error =
            mountingFromTransform(cv::Vec3d(origin[0], origin[1], origin[2]),
                                  rotationOfQuaternion(cv::Vec4d(quaternion[0], quaternion[1],
                                                                 quaternion[2], quaternion[3])),
                                  base_height_m, camera, warning);
        if (!error.empty()) throw py::value_error(error);
        return py::make_tuple(camera, warning);
      },
      "origin"_a, "quaternion"_a, "base_height_m"_a, "camera"_a,
      "(camera, warning): `camera` with the mounting of an optical frame at `origin` (x, y, z) "
      "turned by `quaternion` (x, y, z, w) in a base frame `base_height_m` above the floor, as "
      "tf gives it; ValueError for a mounting the ground projection cannot model.");
  m.def("same_mounting", &sameMounting, "a"_a, "b"_a, "Whether two cameras' mountings agree.");
  m.def("same_intrinsics", &sameIntrinsics, "a"_a, "b"_a,
        "Whether two cameras' intrinsics (and lens) agree.");
  m.def("describe_mounting", &describeMounting, "camera"_a, "The mounting in words, for logs.");
  m.attr("WAITING_FOR_MOUNTING") = kWaitingForMountingState;
  // The mounting source's ~param defaults (cfg/Camera.cfg; the camera_* ones are CameraGeometry's).
  m.attr("CAMERA_DEFAULTS") = py::dict("camera_mounting"_a = CameraDefaults::camera_mounting,
                                       "base_frame"_a = CameraDefaults::base_frame,
                                       "mounting_timeout"_a = CameraDefaults::mounting_timeout);
}

void bindBeaconController(py::module_& m) {
  py::enum_<BeaconShape> shape(m, "BeaconShape");
  defEnumNames(shape, kBeaconShapeNames);

  py::class_<BeaconObject> object(
      m, "BeaconObject",
      "size_m: a sphere's radius, a box's width facing the camera; depth_m: a box's footprint "
      "behind that face.");
  defEnumField(object, "shape", &BeaconObject::shape, kBeaconShapeNames);
  object.def_readwrite("size_m", &BeaconObject::size_m)
      .def_readwrite("depth_m", &BeaconObject::depth_m);
  defKeywordInit(object, static_cast<Validator<BeaconObject>>(&validate));

  py::class_<RangeEstimate> range(m, "RangeEstimate", "Ranges in m; None when not observable.");
  range.def_readonly("from_size", &RangeEstimate::from_size)
      .def_readonly("from_ground", &RangeEstimate::from_ground)
      .def("best", &RangeEstimate::best);
  defRepr(range);
  m.def("estimate_range", &estimateRange, "blob"_a, "image_width"_a, "image_height"_a, "camera"_a,
        "object"_a);

  py::enum_<BeaconMode> mode(m, "BeaconMode");
  defEnumNames(mode, kBeaconModeNames);

  py::enum_<BeaconState> state(m, "BeaconState");
  defEnumNames(state, kBeaconStateNames);

  using Config = BeaconControllerConfig;
  py::class_<Config> config(m, "BeaconControllerConfig");
  defEnumField(config, "mode", &Config::mode, kBeaconModeNames);
  bindFields(config);
  config.def_readwrite("target", &Config::target).def_readwrite("camera", &Config::camera);
  defKeywordInit(config, static_cast<Validator<Config>>(&validate));
  m.def("check_colours_detected", &checkColoursDetected, "controller"_a, "detector"_a,
        "'' when the detector measures every colour the controller uses, else a message.");

  py::class_<BeaconController>(m, "BeaconController",
                               "Lab 5's follow green / stop at red, or Exercise 10's approach.")
      .def(py::init<const Config&>(), "config"_a = Config())
      .def("update", &BeaconController::update, "blobs"_a, "stamp"_a,
           "The Twist2D for one frame's BlobResult; stamp in seconds.")
      .def_property_readonly("state", &BeaconController::state)
      .def_property_readonly("last_range", [](const BeaconController& c) { return c.lastRange(); })
      .def_property_readonly("last_bearing",
                             [](const BeaconController& c) { return c.lastBearing(); })
      .def_property_readonly(
          "config", [](const BeaconController& c) { return c.config(); }, "A copy of the config.")
      .def("reset", &BeaconController::reset);
}

void bindTagDetector(py::module_& m) {
  py::class_<TagDetectorConfig> config(m, "TagDetectorConfig");
  bindFields(config);
  defKeywordInit(config, static_cast<Validator<TagDetectorConfig>>(&validate));

  py::class_<MarkerObservation> observation(
      m, "MarkerObservation",
      "A marker's pose in the camera optical frame (x right, y down, z forward), metres.");
  observation.def_readwrite("id", &MarkerObservation::id)
      .def_property(
          "corners",
          [](const MarkerObservation& o) {
            py::array_t<double> out({4, 2});
            for (int i = 0; i < 4; ++i) {
              *out.mutable_data(i, 0) = o.corners[i].x;
              *out.mutable_data(i, 1) = o.corners[i].y;
            }
            return out;
          },
          [](MarkerObservation& o, const py::array_t<double, py::array::forcecast>& corners) {
            const auto c = fixedShape(corners, 4, 2, "corners");
            for (int i = 0; i < 4; ++i) o.corners[i] = {c(i, 0), c(i, 1)};
          },
          "4x2 px: TL, TR, BR, BL seen from the front")
      .def_property(
          "rotation", [](const MarkerObservation& o) { return matrixArray(o.rotation); },
          [](MarkerObservation& o, const py::array_t<double, py::array::forcecast>& rotation) {
            const auto r = fixedShape(rotation, 3, 3, "rotation");
            for (int i = 0; i < 9; ++i) o.rotation(i / 3, i % 3) = r(i / 3, i % 3);
          },
          "3x3")
      .def_property(
          "translation",
          [](const MarkerObservation& o) { return py::array_t<double>(3, o.translation.val); },
          [](MarkerObservation& o, const std::array<double, 3>& t) {
            o.translation = {t[0], t[1], t[2]};
          },
          "the marker centre, (3,)")
      .def_readwrite("reprojection_error_px", &MarkerObservation::reprojection_error_px)
      .def_readwrite("quality", &MarkerObservation::quality);
  defKeywordInit(observation);

  py::class_<TagDetector>(
      m, "TagDetector",
      "The parker's AprilTag detector (libapriltag) and pose (IPPE + refinement).")
      .def(py::init<const TagDetectorConfig&>(), "config"_a = TagDetectorConfig())
      .def(
          "detect",
          [](TagDetector& detector, const py::handle& grey, const CameraGeometry& camera) {
            return detector.detect(matView(grey, 1), camera);
          },
          "grey"_a, "camera"_a = CameraGeometry(),
          "The configured tag in an HxW uint8 frame, or None; only the intrinsics are used. "
          "Stateful (the previous pose settles the planar ambiguity).")
      .def("reset", &TagDetector::reset, "Forgets the previous pose.")
      .def_property_readonly(
          "config", [](const TagDetector& d) { return d.config(); }, "A copy of the config.");
}

void bindSteering(py::module_& m) {
  py::enum_<SteeringMode> mode(m, "SteeringMode");
  defEnumNames(mode, kSteeringModeNames);

  py::enum_<LineState> line_state(m, "LineState");
  defEnumNames(line_state, kLineStateNames);

  py::class_<PdConfig> pd(m, "PdConfig", "pd's steering and speed taper.");
  bindFields(pd);
  defKeywordInit(pd);

  py::class_<LineSearchConfig> search(m, "LineSearchConfig",
                                      "The lost-line search, timed from the last sighting.");
  bindFields(search);
  defKeywordInit(search);

  py::class_<PathConfig> path(m, "PathConfig", "path's tracking law and line memory.");
  bindFields(path);
  defKeywordInit(path);

  py::class_<SteeringConfig> config(m, "SteeringConfig",
                                    "One configuration of the three laws, one set of limits.");
  defEnumField(config, "mode", &SteeringConfig::mode, kSteeringModeNames);
  bindFields(config);
  config.def_readwrite("pd", &SteeringConfig::pd)
      .def_readwrite("search", &SteeringConfig::search)
      .def_readwrite("path", &SteeringConfig::path);
  defKeywordInit(config, static_cast<Validator<SteeringConfig>>(&validate));

  py::class_<LineObservation> observation(
      m, "LineObservation",
      "One frame as a steering law sees it: the measurement, its stamp (s), the twist applied "
      "since the previous frame, the command sent after it and the base's measured delay (s, "
      "None: the configured command_latency).");
  observation.def_readwrite("measurement", &LineObservation::measurement)
      .def_readwrite("stamp", &LineObservation::stamp)
      .def_readwrite("applied", &LineObservation::applied)
      .def_readwrite("sent", &LineObservation::sent)
      .def_readwrite("latency", &LineObservation::latency);
  defKeywordInit(observation);

  py::class_<LineSearch>(m, "LineSearch", "The lost-line state machine pd and path use.")
      .def(py::init<const LineSearchConfig&>(), "config"_a = LineSearchConfig())
      .def("seen", &LineSearch::seen, "stamp"_a, "error"_a,
           "The line was seen at `stamp` with normalised error `error`.")
      .def("unseen", &LineSearch::unseen, "stamp"_a,
           "The command for a frame at `stamp` without a sighting.")
      .def_property_readonly("state", &LineSearch::state)
      .def("reset", &LineSearch::reset);

  py::class_<SteeringLaw>(m, "SteeringLaw",
                          "A line measurement in, a Twist2D out; make one with make_steering_law.")
      .def("step", &SteeringLaw::step, "frame"_a, "The command for one LineObservation.")
      .def(
          "step",
          [](SteeringLaw& law, const LineMeasurement& measurement, double stamp,
             const Twist2D& applied, const Twist2D& sent, std::optional<double> latency) {
            return law.step({measurement, stamp, applied, sent, latency});
          },
          "measurement"_a, "stamp"_a, "applied"_a = Twist2D(), "sent"_a = Twist2D(),
          "latency"_a = py::none(), "The command for one frame's measurement at `stamp` (s).")
      .def_property_readonly("state", &SteeringLaw::state)
      .def_property_readonly("mode", &SteeringLaw::mode)
      .def("reset", &SteeringLaw::reset, "Forgets all history.");
  py::class_<LectureLaw, SteeringLaw>(m, "LectureLaw").def(py::init<>());
  py::class_<PdLaw, SteeringLaw>(m, "PdLaw")
      .def(py::init<const SteeringConfig&>(), "config"_a = SteeringConfig());

  using PathState = PathLaw::PathState;
  py::class_<PathState> path_state(m, "PathState", "The remembered path at the base.");
  path_state.def_readonly("valid", &PathState::valid)
      .def_readonly("lateral", &PathState::lateral)
      .def_readonly("heading", &PathState::heading)
      .def_readonly("curvature", &PathState::curvature)
      .def_readonly("points", &PathState::points);
  defRepr(path_state);
  py::class_<PathLaw, SteeringLaw>(m, "PathLaw")
      .def(py::init<const SteeringConfig&, const CameraGeometry&>(), "config"_a, "camera"_a)
      .def_property_readonly("path_state", &PathLaw::pathState)
      .def(
          "path_points",
          [](const PathLaw& law) {
            const std::vector<cv::Point2d> points = law.pathPoints();
            py::array_t<double> out({static_cast<py::ssize_t>(points.size()), py::ssize_t{2}});
            for (size_t i = 0; i < points.size(); ++i) {
              *out.mutable_data(i, 0) = points[i].x;
              *out.mutable_data(i, 1) = points[i].y;
            }
            return out;
          },
          "Nx2 m: the remembered points in base_link (x forward, y left), oldest first.");

  m.def("make_steering_law", &makeSteeringLaw, "config"_a = SteeringConfig(),
        "camera"_a = std::optional<CameraGeometry>(),
        "The law config.mode names; path without a camera gets pd, path's own fallback.");
}

void bindSignDetector(py::module_& m) {
  using Config = SignDetectorConfig;
  py::class_<Config> config(m, "SignDetectorConfig");
  bindFields(config);
  defKeywordInit(config, static_cast<Validator<Config>>(&validate));

  py::class_<SignDetector>(
      m, "SignDetector",
      "The parker's textured-sign detector (SIFT, RANSAC, render-and-align, IPPE) and "
      "tracker.")
      .def(py::init<const Config&>(), "config"_a)
      .def(
          "detect",
          [](SignDetector& detector, const py::handle& grey, const CameraGeometry& camera) {
            const cv::Mat frame = matView(grey, 1);
            py::gil_scoped_release unlocked;
            return detector.detect(frame, camera);
          },
          "grey"_a, "camera"_a = CameraGeometry(),
          "The sign in an HxW uint8 frame (id 0, quality = inliers), or None. Stateful: tracks "
          "the sign from the previous frame.")
      .def("reset", &SignDetector::reset, "Forgets the previous pose and sighting.")
      .def_property_readonly("last_tracked", &SignDetector::lastTracked)
      .def_property_readonly("reference_features", &SignDetector::referenceFeatures)
      .def_property_readonly("height_m", &SignDetector::heightMetres);
}

void bindParkingServo(py::module_& m) {
  py::enum_<ParkingState> parking_state(m, "ParkingState");
  defEnumNames(parking_state, kParkingStateNames);

  using Config = ParkingServoConfig;
  py::class_<Config> config(m, "ParkingServoConfig");
  bindFields(config);
  config.def_readwrite("camera", &Config::camera);
  defKeywordInit(config, static_cast<Validator<Config>>(&validate));

  py::class_<ParkingError> error(m, "ParkingError",
                                 "The marker's pose as the robot needs it, base_link, m and rad.");
  error.def_readonly("along", &ParkingError::along)
      .def_readonly("lateral", &ParkingError::lateral)
      .def_readonly("heading", &ParkingError::heading)
      .def_readonly("phi", &ParkingError::phi)
      .def_readonly("bearing", &ParkingError::bearing);
  defRepr(error);
  m.def("parking_error", &parkingError, "marker"_a, "camera"_a);

  py::class_<ParkingServo>(m, "ParkingServo",
                           "Parks square in front of a marker (ViSP's unicycle servo).")
      .def(py::init<const Config&>(), "config"_a = Config())
      .def("update", &ParkingServo::update, "marker"_a, "time_s"_a,
           "The desired Twist2D for one frame; marker None when not seen.")
      .def("set_intrinsics", &ParkingServo::setIntrinsics, "camera"_a,
           "Takes fx, fy, cx, cy of `camera`; the mounting stays.")
      .def_property_readonly("state", &ParkingServo::state)
      .def_property_readonly("last_error", &ParkingServo::lastError)
      .def_property_readonly(
          "config", [](const ParkingServo& s) { return s.config(); }, "A copy of the config.");
}

}  // namespace
}  // namespace follow_bot

PYBIND11_MODULE(core, m) {
  m.doc() = "follow_bot's C++ detectors and controllers (the nodes' own code) for Python.";
  follow_bot::bindVelocity(m);
  follow_bot::bindWatchdog(m);
  follow_bot::bindGeometry(m);
  follow_bot::bindLineDetector(m);
  follow_bot::bindColourBlobs(m);
  follow_bot::bindBeaconController(m);
  follow_bot::bindTagDetector(m);
  follow_bot::bindSteering(m);
  follow_bot::bindSignDetector(m);
  follow_bot::bindParkingServo(m);
}
