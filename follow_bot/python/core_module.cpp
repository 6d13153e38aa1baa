// follow_bot.core: the ROS-free C++ cores from Python, with no logic of their own. The
// conventions (frames, configs, results) are follow_bot_common/pybind_support.h's; the detectors'
// and controllers' constructors run the same validate() as the configs. The bindings are split
// by area (bindings.h).
#include <pybind11/pybind11.h>

#include "bindings.h"

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
