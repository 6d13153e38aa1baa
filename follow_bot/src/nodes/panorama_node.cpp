// `rosrun follow_bot panorama`: the Panorama nodelet in a process of its own.
#include "follow_bot/ros/nodelets.h"
#include "image_converter/ros/nodelet_main.h"

int main(int argc, char** argv) {
  return image_converter::runNodelet(argc, argv, "panorama", follow_bot::makePanoramaNodelet(),
                                     {{"image", "/camera/rgb/image_raw"},
                                      {"camera_info", "/camera/rgb/camera_info"},
                                      {"cmd_vel", "/cmd_vel"},
                                      {"odom", "/odom"}});
}
