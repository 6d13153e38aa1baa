// The core's images are 8-bit grey, BGR or BGRA; the matcher works on grey, the stitcher on BGR.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace image_converter {

// `image` with `channels` channels, 1 (grey) or 3 (BGR): itself when it has them, else a
// converted copy.
inline cv::Mat withChannels(const cv::Mat& image, int channels) {
  if (image.channels() == channels) return image;
  const bool has_alpha = image.channels() == 4;
  const int code = channels == 1 ? (has_alpha ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY)
                                 : (has_alpha ? cv::COLOR_BGRA2BGR : cv::COLOR_GRAY2BGR);
  cv::Mat converted;
  cv::cvtColor(image, converted, code);
  return converted;
}

}  // namespace image_converter
