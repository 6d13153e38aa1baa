// `rosrun image_converter image_converter`: the ImageConverter nodelet in a process of its own.
#include "image_converter/image_converter_nodelet.h"
#include "image_converter/ros/nodelet_main.h"

int main(int argc, char** argv) {
  return image_converter::runNodelet(argc, argv, "image_converter",
                                     std::make_unique<image_converter::ImageConverterNodelet>());
}
