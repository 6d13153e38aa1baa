// follow_bot.core, the parker: the tag and sign detectors and the parking servo.
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
#include "follow_bot/marker_target.h"
#include "follow_bot/parking_servo.h"
#include "follow_bot/sign_detector.h"
#include "follow_bot/tag_detector.h"
#include "follow_bot_common/ground_projection.h"
#include "follow_bot_common/pybind_support.h"

namespace py = pybind11;
using namespace py::literals;

namespace follow_bot {

using namespace pybind_support;

namespace {

// A read-only 2-D view of `array`, which must be rows x cols (ValueError naming `name` otherwise).
py::detail::unchecked_reference<double, 2> fixedShape(const py::array_t<double>& array, int rows,
                                                      int cols, const char* name) {
  if (array.ndim() != 2 || array.shape(0) != rows || array.shape(1) != cols) {
    throw py::value_error(std::string(name) + " must be " + std::to_string(rows) + "x" +
                          std::to_string(cols) + ", got shape " + shapeOf(array));
  }
  return array.unchecked<2>();
}

}  // namespace

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

}  // namespace follow_bot
