// Factory for the panorama nodelet, so the thin node can run it without pluginlib.
#pragma once

#include <memory>

#include <nodelet/nodelet.h>

namespace image_converter {

std::unique_ptr<nodelet::Nodelet> makePanoramaNodelet();

}  // namespace image_converter
