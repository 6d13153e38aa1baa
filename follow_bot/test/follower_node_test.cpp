// rostest: the follower node through its topics (wall time, no simulator), in lockstep on its
// answers (node_answers.h).
#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>

#include <cmath>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "frame_msg.h"
#include "node_answers.h"
#include "node_test_main.h"

namespace {

class FollowerNode : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(follower_.connect()) << "follower never connected";
    ASSERT_TRUE(watchdog_.connect()) << "follower_watchdog never connected";
  }

  sensor_msgs::Image frame(const cv::Mat& bgr) {
    stamp_ += ros::Duration(1.0 / 30.0);
    return follow_bot::test::bgrFrame(bgr, stamp_);
  }

  ros::NodeHandle nh_;
  // Raised frame watchdogs (follower_node.test): its answers are the frames' alone.
  follow_bot::test::NodeAnswers follower_{nh_, "/follower", "/camera/rgb/image_raw",
                                          "/camera/rgb/camera_info", "/cmd_vel"};
  // The default watchdogs, for the test of frames stopping.
  follow_bot::test::NodeAnswers watchdog_{nh_, "/follower_watchdog", "/watchdog/image",
                                          "/watchdog/camera_info", "/watchdog/cmd_vel"};
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
    const auto answer = follower_.send(frame(floorWithLine(480)));
    ASSERT_TRUE(answer.status) << "frame " << i << " unanswered";
    ASSERT_EQ(answer.twists.size(), 1u) << "frame " << i;
    EXPECT_TRUE(finiteAndLimited(answer.twists[0]));
    last_angular = answer.twists[0].angular.z;
  }
  EXPECT_LT(last_angular, -0.05) << "line right of centre must turn right (negative yaw rate)";
}

TEST_F(FollowerNode, DefinedAnswersForFramesWithoutALine) {
  const cv::Mat grey(480, 640, CV_8UC3, cv::Scalar(120, 120, 120));
  const cv::Mat yellow(480, 640, CV_8UC3, cv::Scalar(0, 220, 255));
  const cv::Mat tiny = floorWithLine(5, 12, 8);  // smaller than the band
  for (const cv::Mat* image : {&grey, &yellow, &tiny}) {
    const auto answer = follower_.send(frame(*image));
    ASSERT_TRUE(answer.status);
    ASSERT_EQ(answer.twists.size(), 1u);
    EXPECT_TRUE(finiteAndLimited(answer.twists[0]));
  }
}

TEST_F(FollowerNode, MalformedFramesAreDroppedWithoutMotionAndTheNodeSurvives) {
  const sensor_msgs::Image good = frame(floorWithLine(320));
  const std::vector<sensor_msgs::Image> bad = follow_bot::test::malformedFrames(good);
  for (size_t i = 0; i < bad.size(); ++i) {
    const auto during = follower_.sendDropped(bad[i]);
    ASSERT_TRUE(during) << "malformed frame " << i << " never counted as dropped";
    EXPECT_TRUE(during->empty()) << "a Twist for malformed frame " << i;
    // The good frame after it gets its one answer.
    const auto answer = follower_.send(frame(floorWithLine(320)));
    ASSERT_TRUE(answer.status) << "follower stopped answering";
    ASSERT_EQ(answer.twists.size(), 1u);
  }
}

TEST_F(FollowerNode, StopsOnceWhenFramesStopAndThenStaysSilent) {
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(watchdog_.send(frame(floorWithLine(320))).status);
  watchdog_.clearTwists();
  const auto& stops = watchdog_.twistsAfter(1.5);  // the watchdog's test: silence is the answer
  ASSERT_EQ(stops.size(), 1u) << "expected exactly one stop command";
  EXPECT_EQ(stops[0].linear.x, 0.0);
  EXPECT_EQ(stops[0].angular.z, 0.0);
}

}  // namespace

int main(int argc, char** argv) {
  return follow_bot::test::runNodeTests(argc, argv, "follower_node_test");
}
