// follow_bot.core, the shared vocabulary: Twist2D and the velocity limiter, the frame watchdog, the
// camera geometry and its mounting from tf.
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
#include "follow_bot_common/CameraDefaults.h"
#include "follow_bot_common/camera_mounting.h"
#include "follow_bot_common/frame_watchdog.h"
#include "follow_bot_common/ground_projection.h"
#include "follow_bot_common/pybind_support.h"
#include "follow_bot_common/velocity_limiter.h"

namespace py = pybind11;
using namespace py::literals;

namespace follow_bot {

using namespace pybind_support;

void bindVelocity(py::module_& m) {
  py::class_<Twist2D> twist(m, "Twist2D",
                            "A planar command (REP-103): linear m/s forward, angular rad/s, "
                            "positive = turning left.");
  twist.def_readwrite("linear", &Twist2D::linear).def_readwrite("angular", &Twist2D::angular);
  defKeywordInit(twist);

  py::class_<VelocityLimiterConfig> config(m, "VelocityLimiterConfig");
  bindFields(config);
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

}  // namespace follow_bot
