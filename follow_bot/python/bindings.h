// The parts of follow_bot.core, one function per area (bind_*.cpp), which core_module.cpp's
// PYBIND11_MODULE calls in order: a class a later one refers to is bound first.
#pragma once

#include <pybind11/pybind11.h>

namespace follow_bot {

// bind_common.cpp: Twist2D, VelocityLimiter, FrameWatchdog, CameraGeometry and the mounting.
void bindVelocity(pybind11::module_& m);
void bindWatchdog(pybind11::module_& m);
void bindGeometry(pybind11::module_& m);
// bind_line.cpp: the line detector and the steering laws.
void bindLineDetector(pybind11::module_& m);
void bindSteering(pybind11::module_& m);
// bind_beacons.cpp: the colour blobs and the beacon controller.
void bindColourBlobs(pybind11::module_& m);
void bindBeaconController(pybind11::module_& m);
// bind_parking.cpp: the tag and sign detectors and the parking servo.
void bindTagDetector(pybind11::module_& m);
void bindSignDetector(pybind11::module_& m);
void bindParkingServo(pybind11::module_& m);

}  // namespace follow_bot
