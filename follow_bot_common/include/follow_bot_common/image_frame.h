// ROS-free description, validation and normalisation of raw camera frames.
//
// A sensor_msgs/Image is just (width, height, encoding, step, data). Before any of it is
// wrapped in a cv::Mat the fields must agree, or OpenCV would read past the buffer. This
// header checks that agreement and turns every supported encoding into BGR8.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

namespace follow_bot_common {

// The encodings every node in this project accepts (sensor_msgs/image_encodings names).
enum class Encoding { kBgr8, kRgb8, kBgra8, kRgba8, kMono8, kMono16 };

// Largest accepted width or height; anything bigger is a corrupt header, not a camera.
constexpr std::uint32_t kMaxDimension = 16384;

// Maps an encoding name to the supported set. "8UC1" and "8UC3" are treated as mono8 and bgr8.
std::optional<Encoding> parseEncoding(const std::string& name);

int channels(Encoding encoding);
int bytesPerPixel(Encoding encoding);
// The OpenCV type (CV_8UC3, CV_16UC1, ...) of one frame in this encoding.
int cvType(Encoding encoding);

// The header fields and buffer of a frame, as they arrive (possibly inconsistent).
struct RawFrame {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::string encoding;
  bool big_endian = false;  // byte order of multi-byte pixel values
  std::uint32_t step = 0;   // bytes per row
  const std::uint8_t* data = nullptr;
  std::size_t data_size = 0;
  std::uint32_t stamp_sec = 0;  // header stamp as sent; stamp_nsec must be < 10^9
  std::uint32_t stamp_nsec = 0;
};

// What a node did with one camera frame: accepted, or why it was dropped (FrameCounts).
enum class FrameOutcome {
  kAccepted,
  kBadEncoding,   // not one of the accepted encodings
  kBadSize,       // width, height, step and data size disagree (or are empty or absurd)
  kBadStamp,      // header stamp nanoseconds >= 10^9
  kSizeMismatch,  // a valid frame of a shape the intrinsics in force are not for
  kError,         // an exception while handling it (a case the checks did not foresee)
};

// Result of validating a RawFrame: either the parsed encoding, or a message naming the problem
// and its kind.
struct FrameCheck {
  std::optional<Encoding> encoding;
  std::string error;  // empty when valid
  FrameOutcome outcome = FrameOutcome::kAccepted;
  bool ok() const { return error.empty(); }
};

// The one acceptance test every node applies before touching a frame's pixels: a supported
// encoding, non-empty dimensions within kMaxDimension, a step of at least width x bytes per
// pixel and a whole number of channel values (cv::Mat requires it: an odd mono16 step would
// throw), data size = height x step, and a header stamp whose nanoseconds are < 10^9. Either
// byte order is accepted (frameToBgr8 swaps big-endian mono16). Never reads the pixel data.
FrameCheck checkFrame(const RawFrame& frame);

// A cv::Mat header over a checked frame's buffer (no copy; valid while the buffer lives).
cv::Mat wrapFrame(const RawFrame& frame, Encoding encoding);

// Converts a frame in any supported encoding into a new BGR8 image (always a fresh buffer, so
// the caller may draw on it). mono16 is scaled to 8 bits as value / 256, rounded and saturated.
cv::Mat toBgr8(const cv::Mat& image, Encoding encoding);

// toBgr8 of a checked frame, in either byte order.
cv::Mat frameToBgr8(const RawFrame& frame, Encoding encoding);

}  // namespace follow_bot_common
