// A node that is only a loader: it runs one nodelet in its own process, so the node and the
// nodelet share every line of behaviour.
#pragma once

#include <csignal>
#include <memory>
#include <string>

#include <nodelet/nodelet.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>

namespace follow_bot {

namespace detail {
inline volatile std::sig_atomic_t& shutdownRequested() {
  static volatile std::sig_atomic_t requested = 0;
  return requested;
}
inline void requestShutdown(int) { shutdownRequested() = 1; }
}  // namespace detail

// Runs `nodelet` as node `default_name`, with the command line's remappings (the nodelet's
// topics are relative, so the node and the nodelet resolve them alike). On SIGINT the nodelet is
// destroyed while ROS is still up, so a behaviour's destructor can still publish its final stop
// command. Returns the exit code: 1 when the nodelet fails to start (bad parameters), 0 after a
// normal shutdown.
inline int runNodelet(int argc, char** argv, const std::string& default_name,
                      std::unique_ptr<nodelet::Nodelet> nodelet) {
  ros::init(argc, argv, default_name, ros::init_options::NoSigintHandler);
  std::signal(SIGINT, detail::requestShutdown);
  std::signal(SIGTERM, detail::requestShutdown);
  const nodelet::M_string remappings = ros::names::getRemappings();
  nodelet::V_string my_argv(argv + 1, argv + argc);
  try {
    nodelet->init(ros::this_node::getName(), remappings, my_argv);
  } catch (const std::exception&) {
    return 1;  // the nodelet has logged why (CheckedNodelet)
  }
  ros::CallbackQueue& queue = *ros::getGlobalCallbackQueue();
  while (ros::ok() && !detail::shutdownRequested()) {
    queue.callAvailable(ros::WallDuration(0.05));
  }
  nodelet.reset();
  ros::shutdown();
  return 0;
}

}  // namespace follow_bot
