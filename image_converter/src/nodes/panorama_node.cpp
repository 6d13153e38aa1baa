// `rosrun image_converter panorama`: the panorama nodelet in a process of its own.
#include "image_converter/panorama_nodelet.h"
#include "image_converter/ros/nodelet_main.h"

int main(int argc, char** argv) {
  return image_converter::runNodelet(argc, argv, "panorama", image_converter::makePanoramaNodelet(),
                                     {{"image", "/camera/rgb/image_raw"},
                                      {"camera_info", "/camera/rgb/camera_info"},
                                      {"odom", "/odom"}});
}
