#include "follow_bot_common/image_frame.h"

#include <opencv2/imgproc.hpp>

namespace follow_bot_common {

std::optional<Encoding> parseEncoding(const std::string& name) {
  if (name == "bgr8" || name == "8UC3") return Encoding::kBgr8;
  if (name == "rgb8") return Encoding::kRgb8;
  if (name == "bgra8") return Encoding::kBgra8;
  if (name == "rgba8") return Encoding::kRgba8;
  if (name == "mono8" || name == "8UC1") return Encoding::kMono8;
  if (name == "mono16") return Encoding::kMono16;
  return std::nullopt;
}

int channels(Encoding encoding) {
  switch (encoding) {
    case Encoding::kBgr8:
    case Encoding::kRgb8:
      return 3;
    case Encoding::kBgra8:
    case Encoding::kRgba8:
      return 4;
    case Encoding::kMono8:
    case Encoding::kMono16:
      return 1;
  }
  return 0;
}

int bytesPerPixel(Encoding encoding) {
  return encoding == Encoding::kMono16 ? 2 : channels(encoding);
}

int cvType(Encoding encoding) {
  return encoding == Encoding::kMono16 ? CV_16UC1 : CV_8UC(channels(encoding));
}

FrameCheck checkFrame(const RawFrame& frame) {
  FrameCheck result;
  result.encoding = parseEncoding(frame.encoding);
  if (!result.encoding) {
    result.error = "unsupported encoding '" + frame.encoding +
                   "' (supported: bgr8, rgb8, bgra8, rgba8, mono8, mono16, 8UC1, 8UC3)";
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
  cv::Mat bgr;
  switch (encoding) {
    case Encoding::kBgr8:
      bgr = image.clone();
      break;
    case Encoding::kRgb8:
      cv::cvtColor(image, bgr, cv::COLOR_RGB2BGR);
      break;
    case Encoding::kBgra8:
      cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
      break;
    case Encoding::kRgba8:
      cv::cvtColor(image, bgr, cv::COLOR_RGBA2BGR);
      break;
    case Encoding::kMono8:
      cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
      break;
    case Encoding::kMono16: {
      cv::Mat mono8;
      image.convertTo(mono8, CV_8U, 1.0 / 256.0);
      cv::cvtColor(mono8, bgr, cv::COLOR_GRAY2BGR);
      break;
    }
  }
  return bgr;
}

}  // namespace follow_bot_common
