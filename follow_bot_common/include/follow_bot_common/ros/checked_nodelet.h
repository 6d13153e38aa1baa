// A nodelet whose start-up failure is logged with its reason: a nodelet manager only reports
// "Failed to load nodelet", so without this a bad ~param would go unexplained.
#pragma once

#include <exception>

#include <nodelet/nodelet.h>

namespace follow_bot {

class CheckedNodelet : public nodelet::Nodelet {
 protected:
  // The nodelet's start-up; throws (std::invalid_argument for a bad ~param) when it cannot run.
  virtual void init() = 0;

 private:
  void onInit() final {
    try {
      init();
    } catch (const std::exception& error) {
      NODELET_FATAL("%s cannot start: %s", getName().c_str(), error.what());
      throw;
    }
  }
};

}  // namespace follow_bot
