// `rosrun follow_bot parker`: the Parker nodelet in a process of its own.
#include "follow_bot/ros/nodelets.h"
#include "image_converter/ros/nodelet_main.h"

int main(int argc, char** argv) {
  return image_converter::runNodelet(argc, argv, "parker", follow_bot::makeParkerNodelet(),
                                     {{"image", "/camera/rgb/image_raw"},
                                      {"camera_info", "/camera/rgb/camera_info"},
                                      {"cmd_vel", "/cmd_vel"}});
}
