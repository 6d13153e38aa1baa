// rostest: the parker node through its topics (wall time, no simulator), in lockstep on its
// answers (node_answers.h): no pose and no motion without usable camera_info, a pose for every
// frame with the tag once it has intrinsics, one Twist per frame, malformed frames dropped and
// survived, and one stop when frames stop.
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "frame_msg.h"
#include "node_answers.h"
#include "node_test_main.h"
#include "synthetic_tag.h"

namespace {

using follow_bot::test::NodeAnswers;

sensor_msgs::CameraInfo cameraInfo(double f) {
  sensor_msgs::CameraInfo info;
  info.width = 640;
  info.height = 480;
  info.K = {f, 0, 320, 0, f, 240, 0, 0, 1};
  return info;
}

class ParkerNode : public ::testing::Test {
 protected:
  void SetUp() override {
    poses_sub_ = nh_.subscribe("/parker/target_pose", 100, &ParkerNode::onPose, this);
    ASSERT_TRUE(parker_.connect()) << "parker never connected";
    ASSERT_TRUE(watchdog_.connect()) << "parker_watchdog never connected";
    ASSERT_TRUE(NodeAnswers::spinUntil([this] { return poses_sub_.getNumPublishers() > 0; }));
  }

  void onPose(const geometry_msgs::PoseStampedConstPtr& msg) { poses_.push_back(*msg); }

  // One frame to the parker: its answer; poses_ then holds what came since the last frame.
  NodeAnswers::Answer send(const sensor_msgs::Image& msg) {
    poses_.clear();
    return parker_.send(msg);
  }

  sensor_msgs::Image frame(const cv::Mat& bgr) {
    stamp_ += ros::Duration(1.0 / 30.0);
    return follow_bot::test::bgrFrame(bgr, stamp_);
  }

  // The harness camera looking straight at the 0.30 m tag id 0, 1.5 m away. Rendered once.
  sensor_msgs::Image tagFrame() {
    static const cv::Mat bgr = [] {
      cv::Mat gray(480, 640, CV_8UC1, cv::Scalar(120));
      const follow_bot::test::TagView view = follow_bot::test::viewFrom(1.5, 0.0, 0.0);
      follow_bot::test::drawTag(gray, follow_bot_common::CameraGeometry{}, 0, 0.30, view.rotation,
                                view.translation);
      cv::Mat out;
      cv::cvtColor(gray, out, cv::COLOR_GRAY2BGR);
      return out;
    }();
    return frame(bgr);
  }

  ros::NodeHandle nh_;
  // Raised frame watchdogs (parker_node.test): its answers are the frames' alone.
  NodeAnswers parker_{nh_, "/parker", "/camera/rgb/image_raw", "/camera/rgb/camera_info",
                      "/cmd_vel"};
  // The default watchdogs, for the test of frames stopping.
  NodeAnswers watchdog_{nh_, "/parker_watchdog", "/watchdog/image", "/watchdog/camera_info",
                        "/watchdog/cmd_vel"};
  ros::Subscriber poses_sub_;
  std::vector<geometry_msgs::PoseStamped> poses_;
  ros::Time stamp_{1000.0};
};

bool still(const geometry_msgs::Twist& t) { return t.linear.x == 0.0 && t.angular.z == 0.0; }

bool finiteAndLimited(const geometry_msgs::Twist& t) {
  return std::isfinite(t.linear.x) && std::isfinite(t.angular.z) && std::abs(t.linear.x) <= 0.7 &&
         std::abs(t.angular.z) <= M_PI;
}

// Runs first (gtest keeps file order): the node has never had camera_info. A pose would be
// published after the frame's answer: later frames' answers give it time to arrive, and each
// frame's check sees what came since the one before.
TEST_F(ParkerNode, A_WithoutCameraInfoNoPoseAndTheRobotStaysStill) {
  for (int i = 0; i < 6; ++i) {
    const auto answer = send(tagFrame());
    ASSERT_TRUE(answer.status) << "frame " << i << " unanswered";
    ASSERT_EQ(answer.twists.size(), 1u) << "frame " << i;
    EXPECT_TRUE(still(answer.twists[0]));
    EXPECT_TRUE(poses_.empty());
  }
}

TEST_F(ParkerNode, B_AllZeroCameraInfoIsIgnored) {
  const std::optional<bool> taken = parker_.sendCameraInfo(cameraInfo(0.0));
  ASSERT_TRUE(taken) << "the camera_info was never counted";
  EXPECT_FALSE(*taken);
  for (int i = 0; i < 6; ++i) {
    const auto answer = send(tagFrame());
    ASSERT_TRUE(answer.status);
    ASSERT_EQ(answer.twists.size(), 1u);
    EXPECT_TRUE(still(answer.twists[0]));
    EXPECT_TRUE(poses_.empty());
  }
}

TEST_F(ParkerNode, C_WithIntrinsicsAPosePerFrameAndOneTwistPerFrame) {
  const std::optional<bool> taken = parker_.sendCameraInfo(cameraInfo(554.256));
  ASSERT_TRUE(taken && *taken) << "the camera_info was not taken";
  std::string state;
  for (int i = 0; i < 10; ++i) {
    const auto answer = send(tagFrame());
    ASSERT_TRUE(answer.status) << "frame " << i << " unanswered";
    ASSERT_EQ(answer.twists.size(), 1u) << "frame " << i;
    EXPECT_TRUE(finiteAndLimited(answer.twists[0]));
    NodeAnswers::spinUntil([this] { return !poses_.empty(); });  // published after the answer
    ASSERT_EQ(poses_.size(), 1u) << "frame " << i;
    const geometry_msgs::PoseStamped& pose = poses_[0];
    EXPECT_EQ(pose.header.frame_id, "camera_rgb_optical_frame");
    EXPECT_NEAR(pose.pose.position.z, 1.5, 0.02);
    EXPECT_NEAR(pose.pose.position.x, 0.0, 0.01);
    // Face-on: the marker frame is the optical frame's orientation (identity quaternion).
    EXPECT_NEAR(std::abs(pose.pose.orientation.w), 1.0, 0.01);
    state = answer.status->state;
  }
  EXPECT_EQ(state, "approaching");
  // A frame without the tag: no pose, and the robot holds (lost), one Twist.
  const cv::Mat grey(480, 640, CV_8UC3, cv::Scalar(120, 120, 120));
  const auto answer = send(frame(grey));
  ASSERT_TRUE(answer.status);
  ASSERT_EQ(answer.twists.size(), 1u);
  EXPECT_EQ(answer.status->state, "lost");
  const auto next = send(frame(grey));  // what came after the lost frame's answer
  ASSERT_TRUE(next.status);
  EXPECT_TRUE(poses_.empty());
}

TEST_F(ParkerNode, D_MalformedFramesAreDroppedWithoutMotionAndTheNodeSurvives) {
  const sensor_msgs::Image good = tagFrame();
  const std::vector<sensor_msgs::Image> bad = follow_bot::test::malformedFrames(good);
  for (size_t i = 0; i < bad.size(); ++i) {
    const auto during = parker_.sendDropped(bad[i]);
    ASSERT_TRUE(during) << "malformed frame " << i << " never counted as dropped";
    EXPECT_TRUE(during->empty()) << "a Twist for malformed frame " << i;
    const auto answer = send(tagFrame());
    ASSERT_TRUE(answer.status) << "parker stopped answering";
    ASSERT_EQ(answer.twists.size(), 1u);
  }
}

TEST_F(ParkerNode, E_StopsOnceWhenFramesStopAndThenStaysSilent) {
  const std::optional<bool> taken = watchdog_.sendCameraInfo(cameraInfo(554.256));
  ASSERT_TRUE(taken && *taken) << "the camera_info was not taken";
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(watchdog_.send(tagFrame()).status);
  watchdog_.clearTwists();
  const auto& stops = watchdog_.twistsAfter(1.5);  // the watchdog's test: silence is the answer
  ASSERT_EQ(stops.size(), 1u) << "expected exactly one stop command";
  EXPECT_TRUE(still(stops[0]));
}

}  // namespace

int main(int argc, char** argv) {
  return follow_bot::test::runNodeTests(argc, argv, "parker_node_test");
}
