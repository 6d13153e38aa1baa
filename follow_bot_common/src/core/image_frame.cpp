#include "follow_bot_common/image_frame.h"

#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace follow_bot_common {

namespace {

// One row per supported encoding: its names and how it becomes BGR8.
struct EncodingInfo {
  Encoding encoding;
  const char* name;   // sensor_msgs/image_encodings
  const char* alias;  // the OpenCV type name some drivers send instead, or nullptr
  int channels;
  int value_bytes;  // of one channel value: 1, or 2 for 16-bit
  int to_bgr;       // the cv::cvtColor code from its 8-bit form; -1: it is BGR8 already
};

constexpr EncodingInfo kEncodings[] = {
    {Encoding::kBgr8, "bgr8", "8UC3", 3, 1, -1},
    {Encoding::kRgb8, "rgb8", nullptr, 3, 1, cv::COLOR_RGB2BGR},
    {Encoding::kBgra8, "bgra8", nullptr, 4, 1, cv::COLOR_BGRA2BGR},
    {Encoding::kRgba8, "rgba8", nullptr, 4, 1, cv::COLOR_RGBA2BGR},
    {Encoding::kMono8, "mono8", "8UC1", 1, 1, cv::COLOR_GRAY2BGR},
    {Encoding::kMono16, "mono16", nullptr, 1, 2, cv::COLOR_GRAY2BGR},
};

const EncodingInfo& infoOf(Encoding encoding) {
  for (const EncodingInfo& info : kEncodings) {
    if (info.encoding == encoding) return info;
  }
  throw std::logic_error("an Encoding without a row in kEncodings");
}

// "bgr8, rgb8, ..., 8UC3, 8UC1": the names, then the aliases.
std::string supportedEncodings() {
  std::string names, aliases;
  for (const EncodingInfo& info : kEncodings) {
    names += std::string(names.empty() ? "" : ", ") + info.name;
    if (info.alias != nullptr) aliases += std::string(", ") + info.alias;
  }
  return names + aliases;
}

}  // namespace

std::optional<Encoding> parseEncoding(const std::string& name) {
  for (const EncodingInfo& info : kEncodings) {
    if (name == info.name || (info.alias != nullptr && name == info.alias)) return info.encoding;
  }
  return std::nullopt;
}

int channels(Encoding encoding) { return infoOf(encoding).channels; }

int bytesPerPixel(Encoding encoding) {
  const EncodingInfo& info = infoOf(encoding);
  return info.channels * info.value_bytes;
}

int cvType(Encoding encoding) {
  const EncodingInfo& info = infoOf(encoding);
  return CV_MAKETYPE(info.value_bytes == 2 ? CV_16U : CV_8U, info.channels);
}

FrameCheck checkFrame(const RawFrame& frame) {
  FrameCheck result;
  result.encoding = parseEncoding(frame.encoding);
  if (!result.encoding) {
    result.error =
        "unsupported encoding '" + frame.encoding + "' (supported: " + supportedEncodings() + ")";
    result.outcome = FrameOutcome::kBadEncoding;
    return result;
  }
  if (frame.width == 0 || frame.height == 0) {
    result.error =
        "empty image (" + std::to_string(frame.width) + "x" + std::to_string(frame.height) + ")";
    result.outcome = FrameOutcome::kBadSize;
    return result;
  }
  if (frame.width > kMaxDimension || frame.height > kMaxDimension) {
    result.error = "absurd dimensions " + std::to_string(frame.width) + "x" +
                   std::to_string(frame.height) + " (limit " + std::to_string(kMaxDimension) +
                   " per side)";
    result.outcome = FrameOutcome::kBadSize;
    return result;
  }
  // 64-bit arithmetic: width, height and step are at most 2^32, so no product overflows.
  const std::uint64_t min_step =
      static_cast<std::uint64_t>(frame.width) * bytesPerPixel(*result.encoding);
  if (frame.step < min_step) {
    result.error = "step " + std::to_string(frame.step) +
                   " is less than width x bytes per pixel (" + std::to_string(min_step) + ") for " +
                   frame.encoding;
    result.outcome = FrameOutcome::kBadSize;
    return result;
  }
  // cv::Mat asserts step % (bytes per channel value) == 0; padding must keep values aligned.
  const int value_bytes = CV_ELEM_SIZE1(cvType(*result.encoding));
  if (frame.step % value_bytes != 0) {
    result.error = "step " + std::to_string(frame.step) + " is not a multiple of " +
                   std::to_string(value_bytes) + " bytes (one " + frame.encoding + " value)";
    result.outcome = FrameOutcome::kBadSize;
    return result;
  }
  const std::uint64_t expected_size = static_cast<std::uint64_t>(frame.height) * frame.step;
  if (frame.data_size != expected_size) {
    result.error = "data size " + std::to_string(frame.data_size) + " != height x step (" +
                   std::to_string(expected_size) + ")";
    result.outcome = FrameOutcome::kBadSize;
    return result;
  }
  if (frame.data == nullptr) {
    result.error = "no pixel buffer";
    result.outcome = FrameOutcome::kBadSize;
    return result;
  }
  if (frame.stamp_nsec >= 1000000000u) {
    result.error = "header stamp nanoseconds " + std::to_string(frame.stamp_nsec) + " >= 10^9";
    result.outcome = FrameOutcome::kBadStamp;
  }
  return result;
}

cv::Mat wrapFrame(const RawFrame& frame, Encoding encoding) {
  // cv::Mat has no const view; the callers only read through it.
  return cv::Mat(static_cast<int>(frame.height), static_cast<int>(frame.width), cvType(encoding),
                 const_cast<std::uint8_t*>(frame.data), frame.step);
}

cv::Mat frameToBgr8(const RawFrame& frame, Encoding encoding) {
  const cv::Mat image = wrapFrame(frame, encoding);
  if (!frame.big_endian || CV_ELEM_SIZE1(image.type()) == 1) return toBgr8(image, encoding);
  // Big-endian 16-bit values: swap the two bytes of each (cv_bridge would make 2 channels).
  cv::Mat bytes(image.rows, image.cols, CV_8UC2, image.data, image.step);
  cv::Mat swapped(image.rows, image.cols, CV_8UC2);
  const int from_to[] = {0, 1, 1, 0};
  cv::mixChannels(&bytes, 1, &swapped, 1, from_to, 2);
  return toBgr8(cv::Mat(image.rows, image.cols, CV_16UC1, swapped.data, swapped.step), encoding);
}

cv::Mat toBgr8(const cv::Mat& image, Encoding encoding) {
  const EncodingInfo& info = infoOf(encoding);
  if (info.to_bgr < 0) return image.clone();
  cv::Mat eight_bit = image;
  if (info.value_bytes == 2) image.convertTo(eight_bit, CV_8U, 1.0 / 256.0);
  cv::Mat bgr;
  cv::cvtColor(eight_bit, bgr, info.to_bgr);
  return bgr;
}

}  // namespace follow_bot_common
