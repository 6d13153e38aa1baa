// A node's last message (a destructor's stop command) must reach its subscribers.
#pragma once

#include <ros/ros.h>

namespace follow_bot_common {

// Publishes `message` and holds `publisher` for 0.1 s of wall time. roscpp hands a message to its
// poll thread; destroying the last Publisher handle right after drops the connections with the
// message still queued (a base would keep the last speed).
template <class Message>
void publishLast(const ros::Publisher& publisher, const Message& message) {
  publisher.publish(message);
  ros::WallDuration(0.1).sleep();
}

}  // namespace follow_bot_common
