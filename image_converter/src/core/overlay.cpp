#include "image_converter/overlay.h"

#include <opencv2/imgproc.hpp>

namespace image_converter {

std::string validate(const OverlayConfig& config) { return follow_bot_common::checkFields(config); }

bool isValid(const OverlayConfig& config) { return validate(config).empty(); }

bool drawOverlay(cv::Mat& bgr, const OverlayConfig& config) {
  CV_Assert(bgr.type() == CV_8UC3);
  if (bgr.cols <= config.min_image_size || bgr.rows <= config.min_image_size) return false;
  // LINE_8 rather than anti-aliased: the outline is exactly pure red, which tests and users can
  // threshold on.
  cv::circle(bgr, cv::Point(bgr.cols / 2, bgr.rows / 2), config.radius_px, cv::Scalar(0, 0, 255),
             config.thickness_px, cv::LINE_8);
  return true;
}

}  // namespace image_converter
