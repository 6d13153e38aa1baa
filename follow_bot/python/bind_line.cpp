// follow_bot.core, the line follower: the band detector and the steering laws (lecture, pd, path).
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

#include "follow_bot/common.h"
#include "follow_bot/line_controller.h"
#include "follow_bot/line_detector.h"
#include "follow_bot/line_path.h"
#include "follow_bot/steering_law.h"
#include "follow_bot_common/ground_projection.h"
#include "follow_bot_common/pybind_support.h"

namespace py = pybind11;
using namespace py::literals;

namespace follow_bot {

using namespace pybind_support;

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

}  // namespace follow_bot
