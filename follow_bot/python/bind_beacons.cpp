// follow_bot.core, the beacon chaser: the colour blobs and the beacon controller.
#include "bindings.h"

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
#include "follow_bot_common/ground_projection.h"
#include "follow_bot_common/pybind_support.h"

namespace py = pybind11;
using namespace py::literals;

namespace follow_bot {

using namespace pybind_support;

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

}  // namespace follow_bot
