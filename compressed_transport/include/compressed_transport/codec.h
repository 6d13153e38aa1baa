// JPEG/PNG coding of ROS images, ROS-free: the pixels and the `format` string of a
// sensor_msgs/CompressedImage as ROS's compressed_image_transport writes and reads them
// ("<image encoding>; <jpeg|png> compressed <coded encoding>", e.g. "bgr8; jpeg compressed bgr8").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace compressed_transport {

enum class Format { kJpeg, kPng };

struct EncoderConfig {
  Format format = Format::kJpeg;
  int jpeg_quality = 95;  // [1, 100], the upstream plugin's default
  int png_level = 9;      // [0, 9]

  // Empty when valid, else the first problem, naming the parameter.
  std::string validate() const;
};

// Parses a `~format` parameter value: "jpeg" or "png". Throws std::invalid_argument otherwise.
Format parseFormat(const std::string& name);

struct Encoded {
  std::string format;  // the CompressedImage's format string
  std::vector<std::uint8_t> data;
};

// Codes `image` (pixels in ROS `encoding`: mono8/16, bgr8/16, rgb8/16, bgra8, rgba8). JPEG takes
// 8-bit images only; colour is coded as BGR. Throws std::invalid_argument for an encoding the
// format cannot hold, naming both.
Encoded encode(const cv::Mat& image, const std::string& encoding, const EncoderConfig& config);

struct Decoded {
  cv::Mat image;         // empty on failure
  std::string encoding;  // the ROS encoding of `image`
  std::string error;     // why it failed, when it did
};

// Decodes a CompressedImage's payload. The image comes back in the encoding the format string
// names before ';' (bgr8 or mono8 when it names none, as old publishers write "jpeg"). Never
// throws: a malformed payload or format string is an error.
Decoded decode(const std::vector<std::uint8_t>& data, const std::string& format);

}  // namespace compressed_transport
