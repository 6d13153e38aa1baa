// rostest: the follower node through its topics (wall time, no simulator).
#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>

#include <cmath>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "frame_msg.h"

namespace {

class FollowerNode : public ::testing::Test {
 protected:
  void SetUp() override {
    images_ = nh_.advertise<sensor_msgs::Image>("/camera/rgb/image_raw", 10);
    commands_ = nh_.subscribe("/cmd_vel", 100, &FollowerNode::onCommand, this);
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(20.0);
    while ((images_.getNumSubscribers() == 0 || commands_.getNumPublishers() == 0) &&
           ros::WallTime::now() < deadline) {
      ros::WallDuration(0.01).sleep();
    }
    ASSERT_GT(images_.getNumSubscribers(), 0u) << "follower never subscribed to the camera";
    ASSERT_GT(commands_.getNumPublishers(), 0u) << "follower never advertised /cmd_vel";
  }

  void onCommand(const geometry_msgs::TwistConstPtr& msg) { received_.push_back(*msg); }

  // Publishes a frame and collects what arrives within `wait` seconds.
  std::vector<geometry_msgs::Twist> send(const sensor_msgs::Image& msg, double wait = 0.2) {
    received_.clear();
    images_.publish(msg);
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(wait);
    while (ros::WallTime::now() < deadline) {
      ros::spinOnce();
      ros::WallDuration(0.002).sleep();
    }
    return received_;
  }

  sensor_msgs::Image frame(const cv::Mat& bgr) {
    stamp_ += ros::Duration(1.0 / 30.0);
    return follow_bot::test::bgrFrame(bgr, stamp_);
  }

  ros::NodeHandle nh_;
  ros::Publisher images_;
  ros::Subscriber commands_;
  std::vector<geometry_msgs::Twist> received_;
  ros::Time stamp_{1000.0};
};

// Grey floor with a yellow vertical stripe centred at `column`.
cv::Mat floorWithLine(int column, int width = 640, int height = 480) {
  cv::Mat bgr(height, width, CV_8UC3, cv::Scalar(120, 120, 120));
  cv::rectangle(bgr, cv::Rect(column - 8, 0, 16, height), cv::Scalar(0, 220, 255), cv::FILLED);
  return bgr;
}

bool finiteAndLimited(const geometry_msgs::Twist& t) {
  return std::isfinite(t.linear.x) && std::isfinite(t.angular.z) && std::abs(t.linear.x) <= 0.7 &&
         std::abs(t.angular.z) <= M_PI && t.linear.y == 0 && t.linear.z == 0 && t.angular.x == 0 &&
         t.angular.y == 0;
}

TEST_F(FollowerNode, AnswersEveryFrameWithExactlyOneTwistAndSteersTowardTheLine) {
  double last_angular = 0.0;
  for (int i = 0; i < 20; ++i) {
    const auto replies = send(frame(floorWithLine(480)), 0.1);
    ASSERT_EQ(replies.size(), 1u) << "frame " << i;
    EXPECT_TRUE(finiteAndLimited(replies[0]));
    last_angular = replies[0].angular.z;
  }
  EXPECT_LT(last_angular, -0.05) << "line right of centre must turn right (negative yaw rate)";
}

TEST_F(FollowerNode, DefinedAnswersForFramesWithoutALine) {
  const cv::Mat grey(480, 640, CV_8UC3, cv::Scalar(120, 120, 120));
  const cv::Mat yellow(480, 640, CV_8UC3, cv::Scalar(0, 220, 255));
  const cv::Mat tiny = floorWithLine(5, 12, 8);  // smaller than the band
  for (const cv::Mat* image : {&grey, &yellow, &tiny}) {
    const auto replies = send(frame(*image), 0.1);
    ASSERT_EQ(replies.size(), 1u);
    EXPECT_TRUE(finiteAndLimited(replies[0]));
  }
}

TEST_F(FollowerNode, MalformedFramesNeverProduceMotionAndTheNodeSurvives) {
  const sensor_msgs::Image good = frame(floorWithLine(320));
  const std::vector<sensor_msgs::Image> bad = follow_bot::test::malformedFrames(good);
  for (const auto& msg : bad) {
    for (const auto& reply : send(msg, 0.1)) {
      // Only the watchdog may speak here, and it only ever says stop.
      EXPECT_EQ(reply.linear.x, 0.0);
      EXPECT_EQ(reply.angular.z, 0.0);
    }
    // The good frame's answer comes last; the watchdog's one stop may precede it, since bad
    // frames do not count as frames.
    const auto replies = send(frame(floorWithLine(320)), 0.2);
    ASSERT_GE(replies.size(), 1u) << "follower stopped answering";
    ASSERT_LE(replies.size(), 2u);
    if (replies.size() == 2) EXPECT_EQ(replies[0].linear.x, 0.0);
  }
}

TEST_F(FollowerNode, StopsOnceWhenFramesStopAndThenStaysSilent) {
  for (int i = 0; i < 10; ++i) send(frame(floorWithLine(320)), 0.03);
  received_.clear();
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(1.5);
  while (ros::WallTime::now() < deadline) {
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
  ASSERT_EQ(received_.size(), 1u) << "expected exactly one stop command";
  EXPECT_EQ(received_[0].linear.x, 0.0);
  EXPECT_EQ(received_[0].angular.z, 0.0);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "follower_node_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
