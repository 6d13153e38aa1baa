// rostest: the parker node through its topics (wall time, no simulator): no pose and no motion
// without usable camera_info, a pose for every frame with the tag once it has intrinsics, one
// Twist per frame, malformed frames survived, and one stop when frames stop.
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/String.h>

#include <cmath>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "frame_msg.h"
#include "synthetic_tag.h"

namespace {

class ParkerNode : public ::testing::Test {
 protected:
  void SetUp() override {
    images_ = nh_.advertise<sensor_msgs::Image>("/camera/rgb/image_raw", 10);
    info_ = nh_.advertise<sensor_msgs::CameraInfo>("/camera/rgb/camera_info", 1, true);
    commands_ = nh_.subscribe("/cmd_vel", 100, &ParkerNode::onCommand, this);
    poses_ = nh_.subscribe("/parker/target_pose", 100, &ParkerNode::onPose, this);
    states_ = nh_.subscribe("/parker/state", 100, &ParkerNode::onState, this);
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(20.0);
    while ((images_.getNumSubscribers() == 0 || commands_.getNumPublishers() == 0 ||
            states_.getNumPublishers() == 0) &&
           ros::WallTime::now() < deadline) {
      ros::WallDuration(0.01).sleep();
    }
    ASSERT_GT(images_.getNumSubscribers(), 0u) << "parker never subscribed to the camera";
    ASSERT_GT(commands_.getNumPublishers(), 0u) << "parker never advertised /cmd_vel";
  }

  void onCommand(const geometry_msgs::TwistConstPtr& msg) { commands_received_.push_back(*msg); }
  void onPose(const geometry_msgs::PoseStampedConstPtr& msg) { poses_received_.push_back(*msg); }
  void onState(const std_msgs::StringConstPtr& msg) { last_state_ = msg->data; }

  void spinFor(double seconds) {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(seconds);
    while (ros::WallTime::now() < deadline) {
      ros::spinOnce();
      ros::WallDuration(0.002).sleep();
    }
  }

  // Publishes a frame and collects the Twists that arrive within `wait` seconds.
  std::vector<geometry_msgs::Twist> send(const sensor_msgs::Image& msg, double wait = 0.08) {
    commands_received_.clear();
    poses_received_.clear();
    images_.publish(msg);
    spinFor(wait);
    return commands_received_;
  }

  void publishInfo(double f) {
    sensor_msgs::CameraInfo info;
    info.width = 640;
    info.height = 480;
    info.K = {f, 0, 320, 0, f, 240, 0, 0, 1};
    info_.publish(info);
    spinFor(0.3);
  }

  sensor_msgs::Image frame(const cv::Mat& bgr) {
    stamp_ += ros::Duration(1.0 / 30.0);
    return follow_bot::test::bgrFrame(bgr, stamp_);
  }

  // The harness camera looking straight at the 0.30 m tag id 0, 1.5 m away. Rendered once:
  // frames must follow each other faster than the 0.15 s watchdog.
  sensor_msgs::Image tagFrame() {
    static const cv::Mat bgr = [] {
      cv::Mat gray(480, 640, CV_8UC1, cv::Scalar(120));
      const follow_bot::test::TagView view = follow_bot::test::viewFrom(1.5, 0.0, 0.0);
      follow_bot::test::drawTag(gray, follow_bot::CameraGeometry{}, 0, 0.30, view.rotation,
                                view.translation);
      cv::Mat out;
      cv::cvtColor(gray, out, cv::COLOR_GRAY2BGR);
      return out;
    }();
    return frame(bgr);
  }

  ros::NodeHandle nh_;
  ros::Publisher images_;
  ros::Publisher info_;
  ros::Subscriber commands_;
  ros::Subscriber poses_;
  ros::Subscriber states_;
  std::vector<geometry_msgs::Twist> commands_received_;
  std::vector<geometry_msgs::PoseStamped> poses_received_;
  std::string last_state_;
  ros::Time stamp_{1000.0};
};

bool still(const geometry_msgs::Twist& t) { return t.linear.x == 0.0 && t.angular.z == 0.0; }

bool finiteAndLimited(const geometry_msgs::Twist& t) {
  return std::isfinite(t.linear.x) && std::isfinite(t.angular.z) && std::abs(t.linear.x) <= 0.7 &&
         std::abs(t.angular.z) <= M_PI;
}

// Runs first (gtest keeps file order): the node has never had camera_info.
TEST_F(ParkerNode, A_WithoutCameraInfoNoPoseAndTheRobotStaysStill) {
  send(tagFrame());  // the first frame: rendered now, and the watchdog may have spoken
  for (int i = 0; i < 5; ++i) {
    const auto replies = send(tagFrame());
    ASSERT_EQ(replies.size(), 1u) << "frame " << i;
    EXPECT_TRUE(still(replies[0]));
    EXPECT_TRUE(poses_received_.empty());
  }
}

TEST_F(ParkerNode, B_AllZeroCameraInfoIsIgnored) {
  publishInfo(0.0);
  send(tagFrame());  // after the pause the watchdog's stop may come with this one
  for (int i = 0; i < 5; ++i) {
    const auto replies = send(tagFrame());
    ASSERT_EQ(replies.size(), 1u);
    EXPECT_TRUE(still(replies[0]));
    EXPECT_TRUE(poses_received_.empty());
  }
}

TEST_F(ParkerNode, C_WithIntrinsicsAPosePerFrameAndOneTwistPerFrame) {
  publishInfo(554.256);
  send(tagFrame());  // after the pause the watchdog's stop may come with this one
  for (int i = 0; i < 10; ++i) {
    const auto replies = send(tagFrame());
    ASSERT_EQ(replies.size(), 1u) << "frame " << i;
    EXPECT_TRUE(finiteAndLimited(replies[0]));
    ASSERT_EQ(poses_received_.size(), 1u) << "frame " << i;
    const geometry_msgs::PoseStamped& pose = poses_received_[0];
    EXPECT_EQ(pose.header.frame_id, "camera_rgb_optical_frame");
    EXPECT_NEAR(pose.pose.position.z, 1.5, 0.02);
    EXPECT_NEAR(pose.pose.position.x, 0.0, 0.01);
    // Face-on: the marker frame is the optical frame's orientation (identity quaternion).
    EXPECT_NEAR(std::abs(pose.pose.orientation.w), 1.0, 0.01);
  }
  EXPECT_EQ(last_state_, "approaching");
  // A frame without the tag: no pose, and the robot holds (lost), one Twist.
  const cv::Mat grey(480, 640, CV_8UC3, cv::Scalar(120, 120, 120));
  const auto replies = send(frame(grey));
  ASSERT_EQ(replies.size(), 1u);
  EXPECT_TRUE(poses_received_.empty());
  EXPECT_EQ(last_state_, "lost");
}

TEST_F(ParkerNode, D_MalformedFramesNeverProduceMotionAndTheNodeSurvives) {
  const sensor_msgs::Image good = tagFrame();
  const std::vector<sensor_msgs::Image> bad = follow_bot::test::malformedFrames(good);
  for (const auto& msg : bad) {
    for (const auto& reply : send(msg, 0.1)) {
      EXPECT_TRUE(still(reply));  // only the watchdog may speak, and it only says stop
    }
    const auto replies = send(tagFrame(), 0.2);
    ASSERT_GE(replies.size(), 1u) << "parker stopped answering";
    ASSERT_LE(replies.size(), 2u);
  }
}

TEST_F(ParkerNode, E_StopsOnceWhenFramesStopAndThenStaysSilent) {
  for (int i = 0; i < 10; ++i) send(tagFrame(), 0.03);
  commands_received_.clear();
  spinFor(1.5);
  ASSERT_EQ(commands_received_.size(), 1u) << "expected exactly one stop command";
  EXPECT_TRUE(still(commands_received_[0]));
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "parker_node_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
