// `rosrun image_converter image_converter`: the ImageConverter nodelet in a process of its own.
#include "image_converter/image_converter_nodelet.h"
#include "image_converter/ros/nodelet_main.h"

int main(int argc, char** argv) {
  image_converter::ImageConverterNodelet nodelet;
  return image_converter::runNodelet(argc, argv, "image_converter", nodelet,
                                     {{"image", "/camera/rgb/image_raw"}});
}
