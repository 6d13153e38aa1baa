// rostest: the beacon chaser through its topics (wall time, no simulator), fed bad input.
#include <dynamic_reconfigure/Reconfigure.h>
#include <follow_bot_msgs/BehaviourStatus.h>
#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <cmath>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "frame_msg.h"
#include "node_test_main.h"

namespace {

const cv::Scalar kFloor(120, 120, 120);
const cv::Scalar kGreen(0, 200, 0);  // BGR, as the rgb world's balls
const cv::Scalar kRed(0, 0, 230);

// Grey floor with a ball of `colour` (BGR) centred at `centre`.
cv::Mat floorWithBall(const cv::Scalar& colour, cv::Point centre = {400, 260}, int radius = 40) {
  cv::Mat bgr(480, 640, CV_8UC3, kFloor);
  cv::circle(bgr, centre, radius, colour, cv::FILLED, cv::LINE_AA);
  return bgr;
}

// The harness camera's camera_info: 640x480, 60 deg horizontal field of view.
sensor_msgs::CameraInfo harnessCameraInfo() {
  sensor_msgs::CameraInfo info;
  info.width = 640;
  info.height = 480;
  const double f = 320.0 / std::tan(M_PI / 6.0);
  info.K = {f, 0.0, 320.0, 0.0, f, 240.0, 0.0, 0.0, 1.0};
  return info;
}

bool isZero(const geometry_msgs::Twist& t) { return t.linear.x == 0.0 && t.angular.z == 0.0; }

// Finite, within the default CommandOutput limits, planar.
bool sane(const geometry_msgs::Twist& t) {
  return std::isfinite(t.linear.x) && std::isfinite(t.angular.z) && std::abs(t.linear.x) <= 0.7 &&
         std::abs(t.angular.z) <= M_PI && t.linear.y == 0 && t.linear.z == 0 && t.angular.x == 0 &&
         t.angular.y == 0;
}

// One beacon_chaser instance under its own topic prefix (see beacon_chaser_node.test), with the
// commands it sent (its own: another node's watchdog stop must not count as this one's answer)
// and its ~status answers: frame stamp -> whether a command went out for it.
struct Chaser {
  Chaser(ros::NodeHandle& nh, const std::string& prefix, const std::string& node)
      : images(nh.advertise<sensor_msgs::Image>(prefix + "/image", 10)),
        camera_info(nh.advertise<sensor_msgs::CameraInfo>(prefix + "/camera_info", 1)),
        commands(nh.subscribe<geometry_msgs::Twist>(
            prefix + "/cmd_vel", 100,
            boost::function<void(const geometry_msgs::TwistConstPtr&)>(
                [this](const geometry_msgs::TwistConstPtr& msg) { received.push_back(*msg); }))),
        statuses(nh.subscribe<follow_bot_msgs::BehaviourStatus>(
            node + "/status", 100,
            boost::function<void(const follow_bot_msgs::BehaviourStatusConstPtr&)>(
                [this](const follow_bot_msgs::BehaviourStatusConstPtr& msg) {
                  answers[msg->header.stamp] = msg->command_sent;
                }))) {}
  bool connected() const {
    return images.getNumSubscribers() > 0 && commands.getNumPublishers() > 0 &&
           statuses.getNumPublishers() > 0;
  }

  ros::Publisher images;
  ros::Publisher camera_info;
  std::vector<geometry_msgs::Twist> received;
  ros::Subscriber commands;
  std::map<ros::Time, bool> answers;
  ros::Subscriber statuses;
};

class BeaconChaserNode : public ::testing::Test {
 protected:
  void SetUp() override {
    log_ = nh_.subscribe("/rosout", 100, &BeaconChaserNode::onLog, this);
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(20.0);
    while (!(follow_.connected() && approach_.connected() && watchdog_.connected()) &&
           ros::WallTime::now() < deadline) {
      ros::WallDuration(0.01).sleep();
    }
    ASSERT_TRUE(follow_.connected()) << "beacon_follow never connected";
    ASSERT_TRUE(approach_.connected()) << "beacon_approach never connected";
    ASSERT_TRUE(watchdog_.connected()) << "beacon_watchdog never connected";
  }

  void onLog(const rosgraph_msgs::LogConstPtr& msg) { logs_.push_back(*msg); }

  // Spins for `wait` wall seconds.
  void spinFor(double wait) {
    spinUntil([] { return false; }, wait);
  }

  // Spins until `done()` or for `timeout` seconds of wall time.
  template <typename Done>
  void spinUntil(Done done, double timeout) {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
    while (!done() && ros::WallTime::now() < deadline) {
      ros::spinOnce();
      ros::WallDuration(0.001).sleep();
    }
  }

  // Publishes a frame to `chaser` and returns its commands within `wait` seconds.
  std::vector<geometry_msgs::Twist> send(Chaser& chaser, const sensor_msgs::Image& msg,
                                         double wait = 0.1) {
    chaser.received.clear();
    chaser.images.publish(msg);
    spinFor(wait);
    return chaser.received;
  }

  // Publishes a frame and spins until the node's ~status answers it and, when that answer says
  // a command went out, until the command arrives (up to 10 s: a loaded machine may be slow);
  // then `grace` seconds more to catch any second command. Frames then follow each other well
  // inside the 0.15 s watchdog, which a fixed wait may not.
  std::vector<geometry_msgs::Twist> sendAnswered(Chaser& chaser, const sensor_msgs::Image& msg,
                                                 double grace = 0.03) {
    chaser.received.clear();
    chaser.images.publish(msg);
    spinUntil(
        [&] {
          const auto answer = chaser.answers.find(msg.header.stamp);
          return answer != chaser.answers.end() && (!answer->second || !chaser.received.empty());
        },
        10.0);
    spinFor(grace);
    return chaser.received;
  }

  // 15 frames of `image` to beacon_approach, each after `info`: every one answered by one sane
  // command; `max_linear`: the fastest forward speed among them.
  void approach(const sensor_msgs::CameraInfo& info, const cv::Mat& image, double* max_linear) {
    for (int i = 0; i < 15; ++i) {
      approach_.camera_info.publish(info);
      const auto replies = sendAnswered(approach_, frame(image));
      ASSERT_EQ(replies.size(), 1u) << "frame " << i;
      EXPECT_TRUE(sane(replies[0]));
      *max_linear = std::max(*max_linear, replies[0].linear.x);
    }
  }

  sensor_msgs::Image frame(const cv::Mat& bgr) {
    stamp_ += ros::Duration(1.0 / 30.0);
    return follow_bot::test::bgrFrame(bgr, stamp_);
  }

  // rosout lines from `node` (e.g. "/beacon_approach") at WARN or above that contain `words`.
  int logsFrom(const std::string& node, const std::string& words) const {
    int count = 0;
    for (const rosgraph_msgs::Log& log : logs_) {
      if (log.name == node && log.level >= rosgraph_msgs::Log::WARN &&
          log.msg.find(words) != std::string::npos) {
        ++count;
      }
    }
    return count;
  }

  // logsFrom once at least one such line came (rosout is asynchronous), or after 10 s of wall
  // time without one: 0.
  int waitForLogs(const std::string& node, const std::string& words) {
    spinUntil([&] { return logsFrom(node, words) > 0; }, 10.0);
    return logsFrom(node, words);
  }

  ros::NodeHandle nh_;
  Chaser follow_{nh_, "/follow", "/beacon_follow"};
  Chaser approach_{nh_, "/approach", "/beacon_approach"};
  Chaser watchdog_{nh_, "/watchdog", "/beacon_watchdog"};
  ros::Subscriber log_;
  std::vector<rosgraph_msgs::Log> logs_;
  ros::Time stamp_{1000.0};
};

TEST_F(BeaconChaserNode, MalformedFramesAreDroppedAndEveryGoodFrameGetsOneTwist) {
  const sensor_msgs::Image good = frame(floorWithBall(kGreen));
  const std::vector<sensor_msgs::Image> bad = follow_bot::test::malformedFrames(good);
  for (std::size_t i = 0; i < bad.size(); ++i) {
    for (const auto& reply : send(follow_, bad[i])) {
      EXPECT_TRUE(isZero(reply)) << "bad frame " << i << ": only the watchdog's stop may answer";
    }
    // The good frame's answer comes last; the watchdog's one stop may precede it, since bad
    // frames do not count as frames.
    const auto replies = sendAnswered(follow_, frame(floorWithBall(kGreen)));
    ASSERT_GE(replies.size(), 1u) << "no answer to the good frame after bad frame " << i;
    ASSERT_LE(replies.size(), 2u);
    if (replies.size() == 2) EXPECT_TRUE(isZero(replies[0]));
    EXPECT_TRUE(sane(replies.back()));
  }
  EXPECT_GE(waitForLogs("/beacon_follow", "dropping frame"), 1);
}

TEST_F(BeaconChaserNode, FramesWithoutBeaconsGetOneSearchTwistEach) {
  const cv::Mat grey(480, 640, CV_8UC3, kFloor);
  const cv::Mat tiny(8, 12, CV_8UC3, kFloor);
  for (const cv::Mat* image : {&grey, &tiny}) {
    for (int i = 0; i < 5; ++i) {
      const auto replies = sendAnswered(follow_, frame(*image));
      ASSERT_EQ(replies.size(), 1u);
      EXPECT_TRUE(sane(replies[0]));
      EXPECT_EQ(replies[0].linear.x, 0.0) << "searching spins in place";
    }
  }
}

// Red halts: the first red frame's answer is one zero, past the deceleration bound (driving at
// ~0.2 m/s, the ramp would take several frames), then no cmd_vel at all.
TEST_F(BeaconChaserNode, AllRedStopsAtOnceAndThenGoesQuiet) {
  geometry_msgs::Twist moving;
  for (int i = 0; i < 15; ++i) {
    const auto replies = sendAnswered(follow_, frame(floorWithBall(kGreen)));
    ASSERT_EQ(replies.size(), 1u);
    moving = replies[0];
  }
  ASSERT_GT(moving.linear.x, 0.05) << "a small green ball ahead: drive toward it";
  const cv::Mat red(480, 640, CV_8UC3, kRed);
  int zeros = 0;
  int last_reply = -1;
  for (int i = 0; i < 30; ++i) {  // 1 s of frames at 30 Hz
    const auto replies = sendAnswered(follow_, frame(red));
    ASSERT_LE(replies.size(), 1u);
    if (replies.empty()) continue;
    EXPECT_TRUE(sane(replies[0]));
    EXPECT_EQ(zeros, 0) << "frame " << i << ": a command after the zero";
    zeros += isZero(replies[0]) ? 1 : 0;
    last_reply = i;
  }
  EXPECT_EQ(zeros, 1) << "exactly one zero";
  EXPECT_EQ(last_reply, 0) << "the first red frame's answer is the zero";
}

// All green looks close: holding (idle), so at most one command per frame and all sane.
TEST_F(BeaconChaserNode, AllGreenGivesASaneCommand) {
  const cv::Mat green(480, 640, CV_8UC3, kGreen);
  for (int i = 0; i < 10; ++i) {
    const auto replies = sendAnswered(follow_, frame(green));
    ASSERT_LE(replies.size(), 1u);
    for (const auto& reply : replies) EXPECT_TRUE(sane(reply));
  }
}

TEST_F(BeaconChaserNode, StopsWithinAFifthOfASecondWhenFramesStop) {
  for (int i = 0; i < 10; ++i) sendAnswered(watchdog_, frame(floorWithBall(kGreen)));
  const std::vector<geometry_msgs::Twist>& received = watchdog_.received;
  watchdog_.received.clear();
  const ros::WallTime last_frame = ros::WallTime::now();
  ros::WallTime first_stop;
  const ros::WallTime deadline = last_frame + ros::WallDuration(1.0);
  while (ros::WallTime::now() < deadline) {
    ros::spinOnce();
    if (first_stop.isZero() && !received.empty()) first_stop = ros::WallTime::now();
    ros::WallDuration(0.002).sleep();
  }
  ASSERT_EQ(received.size(), 1u) << "expected exactly one stop command";
  EXPECT_TRUE(isZero(received[0]));
  EXPECT_LE((first_stop - last_frame).toSec(), 0.2);
}

// Approach mode needs intrinsics for ranges: without usable camera_info it holds still and says
// so (throttled); valid camera_info gets it moving.
TEST_F(BeaconChaserNode, ApproachHoldsStillWithoutUsableCameraInfo) {
  const cv::Mat ball = floorWithBall(kGreen, {330, 250});
  const ros::WallTime start = ros::WallTime::now();
  for (int i = 0; i < 30; ++i) {  // >= 3 s of wall time: the warning is throttled to one per 2 s
    const auto replies = sendAnswered(approach_, frame(ball), 0.1);
    ASSERT_EQ(replies.size(), 1u);
    EXPECT_TRUE(isZero(replies[0])) << "no camera_info yet, frame " << i;
  }
  const double elapsed = (ros::WallTime::now() - start).toSec();
  const int warnings = waitForLogs("/beacon_approach", "camera_info");
  EXPECT_GE(warnings, 1) << "holding still must be explained";
  EXPECT_LE(warnings, 1 + static_cast<int>(elapsed / 2.0))
      << "the explanation is throttled to one per 2 s, not one per frame (" << elapsed << " s)";

  sensor_msgs::CameraInfo zeros;  // all-zero K: unusable
  zeros.width = 640;
  zeros.height = 480;
  for (int i = 0; i < 10; ++i) {
    approach_.camera_info.publish(zeros);
    const auto replies = sendAnswered(approach_, frame(ball));
    ASSERT_EQ(replies.size(), 1u);
    EXPECT_TRUE(isZero(replies[0])) << "all-zero camera_info, frame " << i;
  }
  EXPECT_GE(waitForLogs("/beacon_approach", "ignoring camera_info"), 1);

  const sensor_msgs::CameraInfo valid = harnessCameraInfo();
  double max_linear = 0.0;
  ASSERT_NO_FATAL_FAILURE(approach(valid, ball, &max_linear));
  EXPECT_GT(max_linear, 0.05) << "with intrinsics the ball is ranged and approached";
}

// camera_info for 640x480 while the frames come at half that size (a binning camera, a resized
// stream): the intrinsics are scaled to the frame and the ball is ranged and approached. Frames of
// another shape are dropped with an error naming both sizes, and nothing is sent for them.
TEST_F(BeaconChaserNode, ApproachFitsCameraInfoToTheFrameSize) {
  const sensor_msgs::CameraInfo full = harnessCameraInfo();
  const cv::Mat ball = floorWithBall(kGreen, {330, 250});
  cv::Mat half;
  cv::resize(ball, half, cv::Size(320, 240), 0, 0, cv::INTER_AREA);
  double max_linear = 0.0;
  ASSERT_NO_FATAL_FAILURE(approach(full, half, &max_linear));
  EXPECT_GT(max_linear, 0.05) << "the half-size frame is ranged through scaled intrinsics";

  cv::Mat wide;
  cv::resize(ball, wide, cv::Size(1280, 720));
  for (int i = 0; i < 5; ++i) {
    approach_.camera_info.publish(full);
    for (const auto& reply : send(approach_, frame(wide))) {
      EXPECT_TRUE(isZero(reply)) << "frame " << i << ": only the watchdog's stop may answer";
    }
  }
  EXPECT_GE(waitForLogs("/beacon_approach",
                        "dropping frame: the frame is 1280x720 but /approach/camera_info is for "
                        "640x480"),
            1);
}

// Sends one dynamic_reconfigure update (string and double parameters) to `node` and returns
// the configuration its server reports back.
dynamic_reconfigure::Config reconfigure(
    const std::string& node, const std::vector<std::pair<std::string, std::string>>& strs,
    const std::vector<std::pair<std::string, double>>& doubles) {
  dynamic_reconfigure::Reconfigure call;
  for (const auto& [name, value] : strs) {
    dynamic_reconfigure::StrParameter param;
    param.name = name;
    param.value = value;
    call.request.config.strs.push_back(param);
  }
  for (const auto& [name, value] : doubles) {
    dynamic_reconfigure::DoubleParameter param;
    param.name = name;
    param.value = value;
    call.request.config.doubles.push_back(param);
  }
  EXPECT_TRUE(ros::service::call(node + "/set_parameters", call));
  return call.response.config;
}

std::string strIn(const dynamic_reconfigure::Config& config, const std::string& name) {
  for (const auto& param : config.strs) {
    if (param.name == name) return param.value;
  }
  return "<missing>";
}

double doubleIn(const dynamic_reconfigure::Config& config, const std::string& name) {
  for (const auto& param : config.doubles) {
    if (param.name == name) return param.value;
  }
  return std::nan("");
}

// Live updates: applied whole, clamped to the .cfg ranges, or refused whole when the core
// rejects the combination (the server then reports the settings still in force).
TEST_F(BeaconChaserNode, ReconfigureAppliesClampsOrRefusesWhole) {
  ASSERT_TRUE(ros::service::waitForService("/beacon_follow/set_parameters", 10000));
  const cv::Mat green_ball = floorWithBall(kGreen);

  // Swap the roles: green now stops the robot.
  auto config =
      reconfigure("/beacon_follow", {{"follow_colour", "blue"}, {"stop_colour", "green"}}, {});
  EXPECT_EQ(strIn(config, "follow_colour"), "blue");
  EXPECT_EQ(strIn(config, "stop_colour"), "green");
  for (int i = 0; i < 5; ++i) {  // stopped by the stop colour: idle, at most its one zero
    const auto replies = sendAnswered(follow_, frame(green_ball));
    ASSERT_LE(replies.size(), 1u);
    for (const auto& reply : replies) EXPECT_TRUE(isZero(reply)) << "green is the stop colour now";
  }

  // Equal follow and stop colours, together with a valid gain: nothing of it is applied.
  config = reconfigure("/beacon_follow", {{"follow_colour", "green"}}, {{"turn_gain", 2.5}});
  EXPECT_EQ(strIn(config, "follow_colour"), "blue");
  EXPECT_EQ(doubleIn(config, "turn_gain"), 1.5);
  EXPECT_GE(waitForLogs("/beacon_follow", "rejected reconfiguration"), 1);

  // An unknown colour name is refused the same way.
  config = reconfigure("/beacon_follow", {{"follow_colour", "purple"}}, {});
  EXPECT_EQ(strIn(config, "follow_colour"), "blue");

  // Out of range: clamped to the .cfg bound.
  config = reconfigure("/beacon_follow", {}, {{"turn_gain", 50.0}});
  EXPECT_EQ(doubleIn(config, "turn_gain"), 10.0);

  // Back to the defaults: green is followed again.
  config = reconfigure("/beacon_follow", {{"follow_colour", "green"}, {"stop_colour", "red"}},
                       {{"turn_gain", 1.5}});
  EXPECT_EQ(strIn(config, "follow_colour"), "green");
  geometry_msgs::Twist last;
  for (int i = 0; i < 15; ++i) {
    const auto replies = sendAnswered(follow_, frame(green_ball));
    ASSERT_EQ(replies.size(), 1u);
    last = replies[0];
  }
  EXPECT_GT(last.linear.x, 0.05);
}

}  // namespace

int main(int argc, char** argv) {
  return follow_bot::test::runNodeTests(argc, argv, "beacon_chaser_node_test");
}
