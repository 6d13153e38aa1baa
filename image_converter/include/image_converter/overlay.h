// The lecture's overlay: a red circle at the image centre.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "image_converter/ImageConverterDefaults.h"

namespace image_converter {

struct OverlayConfig {
  int radius_px = ImageConverterDefaults::circle_radius;        // circle radius, pixels
  int thickness_px = ImageConverterDefaults::circle_thickness;  // outline thickness, pixels
  int min_image_size = 50;  // the circle is drawn only when width and height exceed this
};

// Empty when the configuration can be drawn (positive radius and thickness, non-negative
// minimum), otherwise a message naming the first bad field.
std::string validate(const OverlayConfig& config);
// validate(config).empty().
bool isValid(const OverlayConfig& config);

// Draws the overlay in place on a BGR8 image. Returns false (and leaves the image untouched)
// when the image is not larger than config.min_image_size in both dimensions.
bool drawOverlay(cv::Mat& bgr, const OverlayConfig& config);

}  // namespace image_converter
