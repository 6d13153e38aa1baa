// The robot's camera topics every node subscribes by default: relative names, resolved in the
// node's (or nodelet's) namespace, so ROS_NAMESPACE and <group ns> move them and a remapping of
// the name `rosnode info` shows applies. Names as a Kinect/openni2 driver publishes them.
#pragma once

namespace follow_bot_common::topics {

inline constexpr char kImage[] = "camera/rgb/image_raw";
inline constexpr char kCameraInfo[] = "camera/rgb/camera_info";

}  // namespace follow_bot_common::topics
