// A nodelet whose start-up failure is logged with its reason: a nodelet manager only reports
// "Failed to load nodelet", so without this a bad ~param would go unexplained. After the start-up
// it names every ~param set that the nodelet did not read (a misspelt name would otherwise be
// ignored without a word): a warning each, or with ~strict_params the start-up's failure.
#pragma once

#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include <nodelet/nodelet.h>

#include "follow_bot_common/NodeStartupDefaults.h"
#include "follow_bot_common/ros/params.h"

namespace follow_bot_common {

class CheckedNodelet : public nodelet::Nodelet {
 protected:
  // The nodelet's start-up; throws (std::invalid_argument for a bad ~param) when it cannot run.
  // Every ~param it reads goes through param() (or noteParamRead), so that it is known.
  virtual void init() = 0;

 private:
  void onInit() final {
    try {
      init();
      checkUnknownParams();
    } catch (const std::exception& error) {
      NODELET_FATAL("%s cannot start: %s", getName().c_str(), error.what());
      throw;
    }
  }

  void checkUnknownParams() {
    const ros::NodeHandle& pnh = getPrivateNodeHandle();
    const bool strict =
        param(pnh, "strict_params", follow_bot_common::NodeStartupDefaults::strict_params);
    const std::vector<UnknownParam> unknown = unknownParams(pnh);
    if (unknown.empty()) return;
    if (strict) {
      std::string error;
      for (const UnknownParam& extra : unknown) {
        error += (error.empty() ? "" : "; ") + extra.describe();
      }
      throw std::invalid_argument(error + " (~strict_params is true)");
    }
    for (const UnknownParam& extra : unknown) {
      NODELET_WARN("%s (ignored)", extra.describe().c_str());
    }
  }
};

}  // namespace follow_bot_common
