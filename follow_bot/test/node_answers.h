// A behaviour node under test, through its topics: frames in; its ~status, cmd_vel and the frame
// counters of its /diagnostics back. Every wait is for an answer, with a timeout, so no wall-clock
// window decides a result: a frame's ~status (and its Twist when the status says one went out),
// a dropped frame or a camera_info counted in the diagnostics.
#pragma once

#include <diagnostic_msgs/DiagnosticArray.h>
#include <follow_bot_msgs/BehaviourStatus.h>
#include <geometry_msgs/Twist.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace follow_bot::test {

class NodeAnswers {
 public:
  static constexpr double kTimeoutS = 10.0;  // for any one answer

  // The node `node` (its name, e.g. "/follower") reading `image` and `camera_info`, commanding
  // on `cmd_vel`.
  NodeAnswers(ros::NodeHandle& nh, const std::string& node, const std::string& image,
              const std::string& camera_info, const std::string& cmd_vel)
      : diagnostics_name_(node.substr(1) + ": behaviour") {
    images_ = nh.advertise<sensor_msgs::Image>(image, 10);
    camera_info_ = nh.advertise<sensor_msgs::CameraInfo>(camera_info, 1, true);
    commands_ = nh.subscribe(cmd_vel, 100, &NodeAnswers::onCommand, this);
    statuses_ = nh.subscribe(node + "/status", 100, &NodeAnswers::onStatus, this);
    diagnostics_ = nh.subscribe("/diagnostics", 100, &NodeAnswers::onDiagnostics, this);
  }

  // Waits (20 s at most) until the node listens to the frames, its answers reach here and its
  // first diagnostics (the counters as they stand) arrived.
  bool connect() {
    return spinUntil(
        [this] {
          return images_.getNumSubscribers() > 0 && commands_.getNumPublishers() > 0 &&
                 statuses_.getNumPublishers() > 0 && !counters_.empty();
        },
        20.0);
  }

  // What the node answered to one frame: its ~status (none: no answer within the timeout) and
  // the Twists that arrived from the frame's publication until then.
  struct Answer {
    std::optional<follow_bot_msgs::BehaviourStatus> status;
    std::vector<geometry_msgs::Twist> twists;
  };

  // Publishes `frame` (its stamp must be new) and waits for its ~status, then for its Twist when
  // the status says one went out.
  Answer send(const sensor_msgs::Image& frame) {
    twists_.clear();
    images_.publish(frame);
    Answer answer;
    spinUntil([&] { return statuses_by_stamp_.count(frame.header.stamp) > 0; }, kTimeoutS);
    const auto found = statuses_by_stamp_.find(frame.header.stamp);
    if (found != statuses_by_stamp_.end()) {
      answer.status = found->second;
      if (answer.status->command_sent) spinUntil([&] { return !twists_.empty(); }, kTimeoutS);
    }
    answer.twists = twists_;
    return answer;
  }

  // Publishes a frame the node must drop and waits until its diagnostics count one more dropped
  // frame; returns the Twists that arrived meanwhile, or nullopt when the drop was never counted.
  std::optional<std::vector<geometry_msgs::Twist>> sendDropped(const sensor_msgs::Image& frame) {
    const long before = framesDropped();
    twists_.clear();
    images_.publish(frame);
    if (!spinUntil([&] { return framesDropped() > before; }, kTimeoutS)) return std::nullopt;
    return twists_;
  }

  // Publishes (latched) `info` and waits until the diagnostics count it, taken or refused;
  // returns whether it was taken (nullopt: never counted).
  std::optional<bool> sendCameraInfo(const sensor_msgs::CameraInfo& info) {
    const long taken = counter("camera_info_accepted");
    const long refused = counter("dropped_bad_camera_info");
    camera_info_.publish(info);
    const bool counted = spinUntil(
        [&] {
          return counter("camera_info_accepted") > taken ||
                 counter("dropped_bad_camera_info") > refused;
        },
        kTimeoutS);
    if (!counted) return std::nullopt;
    return counter("camera_info_accepted") > taken;
  }

  // The Twists heard since the last send, and any that arrive during the next `seconds` of wall
  // time (only for the watchdog's own tests, where silence is the answer).
  const std::vector<geometry_msgs::Twist>& twistsAfter(double seconds) {
    spinUntil([] { return false; }, seconds);
    return twists_;
  }
  void clearTwists() { twists_.clear(); }

  // Spins until `done` (true) or `timeout_s` of wall time has passed (false).
  static bool spinUntil(const std::function<bool()>& done, double timeout_s = kTimeoutS) {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_s);
    while (ros::ok()) {
      ros::spinOnce();
      if (done()) return true;
      if (ros::WallTime::now() > deadline) return false;
      ros::WallDuration(0.002).sleep();
    }
    return false;
  }

  // A counter of the node's latest "<node>: behaviour" diagnostics (0 before any).
  long counter(const std::string& key) const {
    const auto found = counters_.find(key);
    return found == counters_.end() ? 0 : found->second;
  }

  // Every frame dropped, whatever the reason.
  long framesDropped() const {
    long dropped = 0;
    for (const char* key : {"dropped_bad_encoding", "dropped_bad_size", "dropped_bad_stamp",
                            "dropped_size_mismatch", "dropped_error"}) {
      dropped += counter(key);
    }
    return dropped;
  }

 private:
  void onCommand(const geometry_msgs::TwistConstPtr& msg) { twists_.push_back(*msg); }
  void onStatus(const follow_bot_msgs::BehaviourStatusConstPtr& msg) {
    statuses_by_stamp_[msg->header.stamp] = *msg;
  }
  void onDiagnostics(const diagnostic_msgs::DiagnosticArrayConstPtr& msg) {
    for (const auto& status : msg->status) {
      if (status.name != diagnostics_name_) continue;
      for (const auto& value : status.values) {
        if (value.key.rfind("dropped_", 0) == 0 ||
            value.key.find("_accepted") != std::string::npos) {
          counters_[value.key] = std::stol(value.value);
        }
      }
    }
  }

  const std::string diagnostics_name_;
  ros::Publisher images_;
  ros::Publisher camera_info_;
  ros::Subscriber commands_;
  ros::Subscriber statuses_;
  ros::Subscriber diagnostics_;
  std::vector<geometry_msgs::Twist> twists_;
  std::map<ros::Time, follow_bot_msgs::BehaviourStatus> statuses_by_stamp_;
  std::map<std::string, long> counters_;
};

}  // namespace follow_bot::test
