// A node that is only a loader: it runs one nodelet in its own process, so the node and the
// nodelet share every line of behaviour.
#pragma once

#include <csignal>
#include <memory>
#include <string>

#include <nodelet/nodelet.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>

namespace follow_bot_common {

namespace detail {
inline volatile std::sig_atomic_t& shutdownRequested() {
  static volatile std::sig_atomic_t requested = 0;
  return requested;
}
inline volatile std::sig_atomic_t& nodeletRunning() {
  static volatile std::sig_atomic_t running = 0;
  return running;
}
// SIGINT and SIGTERM. Once the nodelet runs: a shutdown that destroys it while ROS is up. Before:
// the end of the process, by the signal itself (roscpp waits for the master without end and
// cannot be told to stop waiting; the nodelet has commanded nothing yet).
inline void onSignal(int signal) {
  if (nodeletRunning()) {
    shutdownRequested() = 1;
    return;
  }
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}
}  // namespace detail

// Runs `nodelet` as node `default_name`, with the command line's remappings (the nodelet's
// topics are relative, so the node and the nodelet resolve them alike). On SIGINT or SIGTERM the
// running nodelet is destroyed while ROS is still up, so a behaviour's destructor can still
// publish its final stop command; during the start-up (also while waiting for the master) the
// process ends at once, killed by the signal. Returns the exit code: 1 when the nodelet fails to
// start (bad parameters), 0 after a normal shutdown.
inline int runNodelet(int argc, char** argv, const std::string& default_name,
                      std::unique_ptr<nodelet::Nodelet> nodelet) {
  std::signal(SIGINT, detail::onSignal);
  std::signal(SIGTERM, detail::onSignal);
  ros::init(argc, argv, default_name, ros::init_options::NoSigintHandler);
  const nodelet::M_string remappings = ros::names::getRemappings();
  nodelet::V_string my_argv(argv + 1, argv + argc);
  try {
    nodelet->init(ros::this_node::getName(), remappings, my_argv);
  } catch (const std::exception&) {
    return 1;  // the nodelet has logged why (CheckedNodelet)
  }
  detail::nodeletRunning() = 1;
  ros::CallbackQueue& queue = *ros::getGlobalCallbackQueue();
  while (ros::ok() && !detail::shutdownRequested()) {
    queue.callAvailable(ros::WallDuration(0.05));
  }
  nodelet.reset();
  ros::shutdown();
  return 0;
}

}  // namespace follow_bot_common
