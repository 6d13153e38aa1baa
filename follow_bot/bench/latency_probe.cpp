// Latency probe: stands in for the camera and the base around a behaviour nodelet.
//
// Publishes ~warmup + ~frames synthetic 640x480 bgr8 frames (a yellow line on grey, drifting a
// little) on `image` at ~rate Hz and listens on `cmd_vel`. The follower answers each frame with
// exactly one Twist, in order, so a frame's latency is the steady-clock time from just before
// publish() to the receipt of its Twist (the header stamp plays no part). Frames go out as
// ImagePtr, so inside one nodelet manager they are handed over without a copy. After the
// uncounted warm-up and ~frames timed frames it prints
//   latency <~label>: median X us, p99 Y us, n=N (goal ...)
// on stdout and shuts ROS down (the whole process: standalone, or the manager it runs in).
//
// Parameters (private): ~frames (600), ~warmup (30), ~rate (30 Hz), ~label ("probe"),
// ~goal_median_us, ~goal_p99_us (<= 0: no goal), ~tcp_nodelay (true: cmd_vel without Nagle),
// ~connect_timeout (10 s to see the follower on both topics), ~answer_timeout (0.1 s).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <geometry_msgs/Twist.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <pluginlib/class_list_macros.hpp>

namespace follow_bot {

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kWidth = 640;
constexpr int kHeight = 480;

// Value at quantile q (0..1) of sorted `v`, nearest rank.
double quantile(const std::vector<double>& sorted, double q) {
  const auto n = static_cast<double>(sorted.size());
  const auto rank = static_cast<size_t>(std::max(1.0, std::ceil(q * n)));
  return sorted[std::min(rank, sorted.size()) - 1];
}

// Frame `i`: grey floor, a slightly slanted yellow line whose position drifts with i.
sensor_msgs::ImagePtr makeFrame(uint32_t i) {
  sensor_msgs::ImagePtr msg(new sensor_msgs::Image);
  msg->header.seq = i;
  msg->header.stamp = ros::Time::now();
  msg->header.frame_id = "camera_rgb_optical_frame";
  msg->width = kWidth;
  msg->height = kHeight;
  msg->encoding = sensor_msgs::image_encodings::BGR8;
  msg->is_bigendian = 0;
  msg->step = kWidth * 3;
  msg->data.resize(static_cast<size_t>(msg->step) * kHeight);
  cv::Mat image(kHeight, kWidth, CV_8UC3, msg->data.data(), msg->step);
  image.setTo(cv::Scalar(110, 115, 120));
  const double centre = kWidth / 2.0 + 60.0 * std::sin(0.05 * i);
  cv::line(image, cv::Point(cvRound(centre - 40.0), 0), cv::Point(cvRound(centre + 40.0), kHeight),
           cv::Scalar(30, 205, 225), 28);
  return msg;
}

std::string goalText(double median_us, double p99_us, double goal_median_us, double goal_p99_us) {
  std::ostringstream text;
  bool met = true;
  if (goal_median_us > 0.0) {
    text << "median <= " << goal_median_us << " us";
    met = met && median_us <= goal_median_us;
  }
  if (goal_p99_us > 0.0) {
    text << (text.tellp() > 0 ? ", " : "") << "p99 <= " << goal_p99_us << " us";
    met = met && p99_us <= goal_p99_us;
  }
  if (text.tellp() == 0) return "no goal";
  text << (met ? ": met" : ": MISSED");
  return text.str();
}

}  // namespace

class LatencyProbeNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    frames_ = std::max(1, pnh.param("frames", 600));
    warmup_ = std::max(0, pnh.param("warmup", 30));
    const double rate = pnh.param("rate", 30.0);
    label_ = pnh.param<std::string>("label", "probe");
    goal_median_us_ = pnh.param("goal_median_us", 0.0);
    goal_p99_us_ = pnh.param("goal_p99_us", 0.0);
    connect_timeout_ = pnh.param("connect_timeout", 10.0);
    answer_timeout_ = std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(pnh.param("answer_timeout", 0.1)));
    if (!std::isfinite(rate) || rate <= 0.0) {
      throw std::invalid_argument("~rate must be > 0, got " + std::to_string(rate));
    }
    ros::TransportHints hints;
    if (pnh.param("tcp_nodelay", true)) hints = ros::TransportHints().tcpNoDelay();
    latencies_us_.reserve(frames_);
    image_pub_ = nh.advertise<sensor_msgs::Image>("image", 1);
    cmd_sub_ = nh.subscribe("cmd_vel", 10, &LatencyProbeNodelet::onCmdVel, this, hints);
    started_ = Clock::now();
    timer_ = nh.createWallTimer(ros::WallDuration(1.0 / rate), &LatencyProbeNodelet::onTick, this);
  }

  void onTick(const ros::WallTimerEvent& /*event*/) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (done_) return;
    if (!connected_ && !waitForConnections()) return;
    if (sent_at_) {
      // One frame in flight: a late answer delays the next frame rather than being matched to
      // it. Past ~answer_timeout (below the follower's 0.15 s watchdog) the frame counts as lost.
      if (Clock::now() - *sent_at_ < answer_timeout_) return;
      if (frame_index_ >= warmup_) ++lost_;
      sent_at_.reset();
    }
    if (sent_ >= warmup_ + frames_) {
      finish();
      return;
    }
    sensor_msgs::ImagePtr frame = makeFrame(static_cast<uint32_t>(sent_));
    sent_at_ = Clock::now();
    frame_index_ = sent_++;
    image_pub_.publish(frame);
  }

  // True once the follower subscribes to `image` and publishes on `cmd_vel`, plus one more tick
  // for the connection headers to settle.
  bool waitForConnections() {
    const bool linked = image_pub_.getNumSubscribers() > 0 && cmd_sub_.getNumPublishers() > 0;
    if (linked && seen_linked_) {
      connected_ = true;
      return true;
    }
    seen_linked_ = linked;
    const double waited = std::chrono::duration<double>(Clock::now() - started_).count();
    if (waited > connect_timeout_) {
      std::printf(
          "latency %s: FAILED, nothing subscribed to %s and published on %s within %.0f s\n",
          label_.c_str(), image_pub_.getTopic().c_str(), cmd_sub_.getTopic().c_str(),
          connect_timeout_);
      std::fflush(stdout);
      done_ = true;
      timer_.stop();
      ros::requestShutdown();
    }
    return false;
  }

  void onCmdVel(const geometry_msgs::TwistConstPtr& /*msg*/) {
    const Clock::time_point received = Clock::now();  // before waiting for the lock
    std::lock_guard<std::mutex> lock(mutex_);
    if (!sent_at_ || received < *sent_at_) {
      ++stray_;  // e.g. a watchdog stop: no frame is waiting for it
      return;
    }
    const double latency_us =
        std::chrono::duration<double, std::micro>(received - *sent_at_).count();
    sent_at_.reset();
    if (frame_index_ >= warmup_) latencies_us_.push_back(latency_us);
  }

  void finish() {
    done_ = true;
    timer_.stop();
    std::vector<double> sorted = latencies_us_;
    std::sort(sorted.begin(), sorted.end());
    if (sorted.empty()) {
      std::printf("latency %s: FAILED, no answer on %s to any of %d frames\n", label_.c_str(),
                  cmd_sub_.getTopic().c_str(), sent_);
    } else {
      const double median = quantile(sorted, 0.5);
      const double p99 = quantile(sorted, 0.99);
      std::string extra;
      if (lost_ > 0) extra += ", " + std::to_string(lost_) + " unanswered";
      if (stray_ > 0) extra += ", " + std::to_string(stray_) + " stray";
      std::printf("latency %s: median %.0f us, p99 %.0f us, n=%zu%s (goal %s)\n", label_.c_str(),
                  median, p99, sorted.size(), extra.c_str(),
                  goalText(median, p99, goal_median_us_, goal_p99_us_).c_str());
    }
    std::fflush(stdout);
    ros::requestShutdown();
  }

  std::mutex mutex_;  // the timer and the cmd_vel callback may run on different threads
  ros::Publisher image_pub_;
  ros::Subscriber cmd_sub_;
  ros::WallTimer timer_;
  int frames_ = 600;
  int warmup_ = 30;
  std::string label_;
  double goal_median_us_ = 0.0;
  double goal_p99_us_ = 0.0;
  double connect_timeout_ = 10.0;
  Clock::duration answer_timeout_;
  Clock::time_point started_;
  bool seen_linked_ = false;
  bool connected_ = false;
  bool done_ = false;
  int sent_ = 0;
  int frame_index_ = 0;                       // of the frame waiting for its answer
  std::optional<Clock::time_point> sent_at_;  // set while a frame waits for its answer
  int lost_ = 0;
  int stray_ = 0;
  std::vector<double> latencies_us_;
};

}  // namespace follow_bot

PLUGINLIB_EXPORT_CLASS(follow_bot::LatencyProbeNodelet, nodelet::Nodelet)
