// The main of a node test that rostest runs: gtest's flags, ros::init as `name`, and one node
// handle held for the whole run (the ROS connection stays up between the tests' own handles).
#pragma once

#include <gtest/gtest.h>
#include <ros/ros.h>

namespace follow_bot::test {

inline int runNodeTests(int argc, char** argv, const char* name) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, name);
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}

}  // namespace follow_bot::test
