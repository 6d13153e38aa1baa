#include "compressed_transport/codec.h"

#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace compressed_transport {

namespace {

std::string trimmed(const std::string& text) {
  const auto first = text.find_first_not_of(' ');
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(' ') - first + 1);
}

int depthOf(const std::string& encoding) {
  if (encoding == "mono8" || encoding == "bgr8" || encoding == "rgb8" || encoding == "bgra8" ||
      encoding == "rgba8") {
    return CV_8U;
  }
  if (encoding == "mono16" || encoding == "bgr16" || encoding == "rgb16") return CV_16U;
  return -1;
}

bool isMono(const std::string& encoding) { return encoding.rfind("mono", 0) == 0; }

// The colour conversion from `from` pixels to BGR(A) for coding, or -1 when none is needed.
int toBgrCode(const std::string& from) {
  if (from == "rgb8" || from == "rgb16") return cv::COLOR_RGB2BGR;
  if (from == "rgba8") return cv::COLOR_RGBA2BGR;
  if (from == "bgra8") return cv::COLOR_BGRA2BGR;
  return -1;
}

}  // namespace

std::string EncoderConfig::validate() const {
  if (jpeg_quality < 1 || jpeg_quality > 100) {
    return "jpeg_quality must be in [1, 100], got " + std::to_string(jpeg_quality);
  }
  if (png_level < 0 || png_level > 9) {
    return "png_level must be in [0, 9], got " + std::to_string(png_level);
  }
  return "";
}

Format parseFormat(const std::string& name) {
  if (name == "jpeg") return Format::kJpeg;
  if (name == "png") return Format::kPng;
  throw std::invalid_argument("format must be jpeg or png, got '" + name + "'");
}

Encoded encode(const cv::Mat& image, const std::string& encoding, const EncoderConfig& config) {
  const int depth = depthOf(encoding);
  const bool jpeg = config.format == Format::kJpeg;
  const std::string name = jpeg ? "jpeg" : "png";
  if (depth < 0 || (jpeg && depth != CV_8U)) {
    throw std::invalid_argument(name + " cannot code images of encoding '" + encoding + "'");
  }
  cv::Mat coded;  // never written into `image`: the caller's pixels (a message's) are read only
  const int code = toBgrCode(encoding);
  if (code >= 0) {
    cv::cvtColor(image, coded, code);
  } else {
    coded = image;
  }
  std::string coded_encoding;
  if (!isMono(encoding)) coded_encoding = depth == CV_8U ? "bgr8" : "bgr16";
  const std::vector<int> params =
      jpeg ? std::vector<int>{cv::IMWRITE_JPEG_QUALITY, config.jpeg_quality}
           : std::vector<int>{cv::IMWRITE_PNG_COMPRESSION, config.png_level};
  Encoded out;
  out.format = encoding + "; " + name + " compressed " + coded_encoding;
  if (!cv::imencode(jpeg ? ".jpg" : ".png", coded, out.data, params)) {
    throw std::invalid_argument(name + " encoding of a " + encoding + " image failed");
  }
  return out;
}

Decoded decode(const std::vector<std::uint8_t>& data, const std::string& format) {
  Decoded out;
  if (data.empty()) {
    out.error = "empty payload";
    return out;
  }
  cv::Mat pixels;
  try {
    pixels = cv::imdecode(data, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& error) {
    out.error = std::string("undecodable payload: ") + error.what();
    return out;
  }
  if (pixels.empty()) {
    out.error =
        "undecodable payload (" + std::to_string(data.size()) + " bytes, format '" + format + "')";
    return out;
  }
  const auto semicolon = format.find(';');
  std::string encoding = semicolon == std::string::npos ? "" : trimmed(format.substr(0, semicolon));
  const int channels = pixels.channels();
  if (encoding.empty()) encoding = channels == 1 ? "mono8" : "bgr8";
  const int depth = depthOf(encoding);
  if (depth < 0) {
    out.error = "unsupported encoding '" + encoding + "' in format '" + format + "'";
    return out;
  }
  const bool want_mono = isMono(encoding);
  if (want_mono && channels != 1) {
    cv::cvtColor(pixels, pixels, channels == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  } else if (!want_mono && channels == 1) {
    cv::cvtColor(pixels, pixels, cv::COLOR_GRAY2BGR);
  } else if (!want_mono && channels == 4 && encoding != "bgra8" && encoding != "rgba8") {
    cv::cvtColor(pixels, pixels, cv::COLOR_BGRA2BGR);
  }
  if (pixels.depth() != depth) {
    pixels.convertTo(pixels, depth, depth == CV_8U ? 1.0 / 257.0 : 257.0);
  }
  if (encoding == "rgb8" || encoding == "rgb16") {
    cv::cvtColor(pixels, pixels, cv::COLOR_BGR2RGB);
  } else if (encoding == "rgba8") {
    cv::cvtColor(pixels, pixels, pixels.channels() == 4 ? cv::COLOR_BGRA2RGBA : cv::COLOR_BGR2RGBA);
  } else if (encoding == "bgra8" && pixels.channels() == 3) {
    cv::cvtColor(pixels, pixels, cv::COLOR_BGR2BGRA);
  }
  out.image = pixels;
  out.encoding = encoding;
  return out;
}

}  // namespace compressed_transport
