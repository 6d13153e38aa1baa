// The lecture's overlay: a red circle at the image centre.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "follow_bot_common/config_fields.h"
#include "image_converter/ImageConverterDefaults.h"

namespace image_converter {

struct OverlayConfig {
  int radius_px = ImageConverterDefaults::circle_radius;        // circle radius, pixels
  int thickness_px = ImageConverterDefaults::circle_thickness;  // outline thickness, pixels
  int min_image_size = 50;  // the circle is drawn only when width and height exceed this

  static constexpr auto fields() {
    using C = OverlayConfig;
    return std::make_tuple(
        follow_bot_common::cfgField("radius_px", &C::radius_px, follow_bot_common::positive(),
                                    "circle_radius"),
        follow_bot_common::cfgField("thickness_px", &C::thickness_px, follow_bot_common::positive(),
                                    "circle_thickness"),
        follow_bot_common::field("min_image_size", &C::min_image_size,
                                 follow_bot_common::atLeast(0)));
  }
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
