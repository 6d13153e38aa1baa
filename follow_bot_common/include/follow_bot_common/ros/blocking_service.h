// A service whose call waits while the nodelet's own callbacks (its camera frames) do the work,
// e.g. turn the robot through a capture: the call runs on a callback queue and thread of its own,
// so that those callbacks keep coming meanwhile.
#pragma once

#include <chrono>
#include <condition_variable>
#include <string>

#include <ros/callback_queue.h>
#include <ros/ros.h>

namespace follow_bot_common {

// Declare it after everything its callback uses: destroyed first, it joins its thread (a call
// in progress ends first) before those go.
class BlockingService {
 public:
  // Advertises `name` (relative to `nh`) answered by `(object->*callback)(request, response)`.
  template <typename T, typename Request, typename Response>
  BlockingService(ros::NodeHandle nh, const std::string& name,
                  bool (T::*callback)(Request&, Response&), T* object) {
    nh.setCallbackQueue(&queue_);
    server_ = nh.advertiseService(name, callback, object);
    spinner_.start();
  }
  ~BlockingService() { spinner_.stop(); }
  BlockingService(const BlockingService&) = delete;
  BlockingService& operator=(const BlockingService&) = delete;

  // In the call: waits with `lock` (held on entry: the mutex the working callbacks share)
  // until `done()` says so, asked at once, on every notify() and at least every `period`
  // (for what no callback reports, e.g. that the callbacks stopped coming).
  template <typename Lock, typename Done>
  void waitUntil(Lock& lock, Done done,
                 std::chrono::milliseconds period = std::chrono::milliseconds(100)) {
    while (!done()) changed_.wait_for(lock, period);
  }
  // From the working callbacks: the waiting call should ask done() again.
  void notify() { changed_.notify_all(); }

 private:
  ros::CallbackQueue queue_;
  ros::AsyncSpinner spinner_{1, &queue_};
  ros::ServiceServer server_;
  std::condition_variable_any changed_;
};

}  // namespace follow_bot_common
