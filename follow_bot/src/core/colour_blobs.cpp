#include "follow_bot/colour_blobs.h"

#include <algorithm>
#include <set>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "follow_bot_common/config_checks.h"

namespace follow_bot {
namespace {

constexpr int kHueCount = 180;  // OpenCV 8-bit hue: 0..179

std::string checkKernel(const char* name, int size) {
  if (size >= 0 && (size <= 1 || size % 2 == 1)) return "";
  std::ostringstream message;
  message << name << " must be 0 (off) or an odd size, got " << size;
  return message.str();
}

std::string checkSpec(const ColourSpec& spec) {
  if (spec.name.empty()) return "name must not be empty";
  for (const std::string& error : {
           requireInRange("hue_centre", spec.hue_centre, 0, kHueCount - 1),
           requireInRange("sensitivity", spec.sensitivity, 0, 90),
           requireInRange("s_min", spec.s_min, 0, 255),
           requireInRange("v_min", spec.v_min, 0, 255),
       }) {
    if (!error.empty()) return error;
  }
  return "";
}

cv::Mat ellipseKernel(int size) {
  if (size <= 1) return cv::Mat();
  return cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(size, size));
}

}  // namespace

std::optional<ColourSpec> parseColourName(const std::string& name) {
  ColourSpec spec;
  spec.name = name;
  if (name == "red") {
    spec.hue_centre = 0;
  } else if (name == "green") {
    spec.hue_centre = 60;
  } else if (name == "blue") {
    spec.hue_centre = 120;
  } else {
    return std::nullopt;
  }
  return spec;
}

std::string colourSpecsFromNames(const std::vector<std::string>& names,
                                 std::vector<ColourSpec>& specs) {
  std::vector<ColourSpec> parsed;
  for (const std::string& name : names) {
    const std::optional<ColourSpec> spec = parseColourName(name);
    if (!spec) return "unknown colour name '" + name + "' (known: red, green, blue)";
    parsed.push_back(*spec);
  }
  specs = parsed;
  return "";
}

std::string validate(const ColourBlobConfig& config) {
  if (config.colours.empty()) return "colours must name at least one colour";
  std::set<std::string> names;
  for (size_t i = 0; i < config.colours.size(); ++i) {
    const ColourSpec& spec = config.colours[i];
    std::string error = checkSpec(spec);
    if (error.empty() && !names.insert(spec.name).second) error = "name is a duplicate";
    if (!error.empty()) {
      std::ostringstream message;
      message << "colours[" << i << "] (" << spec.name << "): " << error;
      return message.str();
    }
  }
  for (const std::string& error : {
           checkKernel("open_kernel", config.open_kernel),
           checkKernel("close_kernel", config.close_kernel),
           requireAtLeast("min_area", config.min_area, 0.0),
       }) {
    if (!error.empty()) return error;
  }
  return "";
}

const ColourBlob* BlobResult::find(const std::string& name) const {
  for (const ColourBlob& blob : colours) {
    if (blob.name == name) return &blob;
  }
  return nullptr;
}

ColourBlobDetector::ColourBlobDetector(const ColourBlobConfig& config)
    : config_(config),
      open_kernel_(ellipseKernel(config.open_kernel)),
      close_kernel_(ellipseKernel(config.close_kernel)) {
  const std::string error = validate(config);
  if (!error.empty()) throw std::invalid_argument("ColourBlobDetector: " + error);
}

void ColourBlobDetector::cleanedMask(const cv::Mat& hsv, const ColourSpec& spec,
                                     cv::Mat& mask) const {
  // The hue window [centre - s, centre + s] on the hue circle is one interval, or two when it
  // crosses 0/179 (red).
  const int low = spec.hue_centre - spec.sensitivity;
  const int high = spec.hue_centre + spec.sensitivity;
  const auto threshold = [&](int hue_low, int hue_high, cv::Mat& out) {
    cv::inRange(hsv, cv::Scalar(hue_low, spec.s_min, spec.v_min), cv::Scalar(hue_high, 255, 255),
                out);
  };
  threshold(std::max(low, 0), std::min(high, kHueCount - 1), mask);
  if (low < 0 || high >= kHueCount) {
    cv::Mat wrapped;
    if (low < 0) {
      threshold(low + kHueCount, kHueCount - 1, wrapped);
    } else {
      threshold(0, high - kHueCount, wrapped);
    }
    cv::bitwise_or(mask, wrapped, mask);
  }
  if (!open_kernel_.empty()) cv::morphologyEx(mask, mask, cv::MORPH_OPEN, open_kernel_);
  if (!close_kernel_.empty()) cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, close_kernel_);
}

BlobResult ColourBlobDetector::detect(const cv::Mat& bgr) const {
  BlobResult result;
  for (const ColourSpec& spec : config_.colours) {
    result.colours.emplace_back();
    result.colours.back().name = spec.name;
  }
  if (bgr.empty()) {
    result.error = "empty frame";
    return result;
  }
  if (bgr.type() != CV_8UC3) {
    result.error = "expected a CV_8UC3 (BGR) frame, got type " + std::to_string(bgr.type());
    return result;
  }
  result.image_width = bgr.cols;
  result.image_height = bgr.rows;

  cv::Mat hsv;
  cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
  cv::Mat mask;
  std::vector<std::vector<cv::Point>> contours;
  std::vector<cv::Point> hull;
  for (size_t i = 0; i < config_.colours.size(); ++i) {
    cleanedMask(hsv, config_.colours[i], mask);
    cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);

    ColourBlob& blob = result.colours[i];
    const std::vector<cv::Point>* largest = nullptr;
    for (const std::vector<cv::Point>& contour : contours) {
      const double area = cv::contourArea(contour);
      if (area < config_.min_area) continue;
      ++blob.blob_count;
      if (largest == nullptr || area > blob.area) {
        largest = &contour;
        blob.area = area;
      }
    }
    if (largest == nullptr) continue;

    blob.found = true;
    // The same circle from the few hull vertices: on long straight runs of boundary pixels
    // minEnclosingCircle takes over 1 ms.
    cv::convexHull(*largest, hull);
    cv::minEnclosingCircle(hull, blob.circle_centre, blob.circle_radius);
    blob.bounding_box = cv::boundingRect(*largest);
    const cv::Moments moments = cv::moments(*largest);
    // A zero-area contour (a line of pixels, only with min_area 0) has no moment centroid.
    blob.centroid = moments.m00 > 0.0
                        ? cv::Point2d(moments.m10 / moments.m00, moments.m01 / moments.m00)
                        : cv::Point2d(blob.circle_centre);
    blob.contour = *largest;
  }
  return result;
}

cv::Mat ColourBlobDetector::mask(const cv::Mat& bgr, const std::string& name) const {
  if (bgr.empty() || bgr.type() != CV_8UC3) return cv::Mat();
  for (const ColourSpec& spec : config_.colours) {
    if (spec.name != name) continue;
    cv::Mat hsv;
    cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
    cv::Mat out;
    cleanedMask(hsv, spec, out);
    return out;
  }
  return cv::Mat();
}

void ColourBlobDetector::drawDebug(cv::Mat& bgr, const BlobResult& blobs) {
  for (const ColourBlob& blob : blobs.colours) {
    if (!blob.found) continue;
    cv::drawContours(bgr, std::vector<std::vector<cv::Point>>{blob.contour}, 0,
                     cv::Scalar(255, 255, 255), 2);
    cv::circle(bgr, blob.circle_centre, static_cast<int>(blob.circle_radius),
               cv::Scalar(0, 255, 255), 1);
    cv::putText(bgr, blob.name, blob.bounding_box.tl() - cv::Point(0, 5), cv::FONT_HERSHEY_SIMPLEX,
                0.6, cv::Scalar(255, 255, 255), 2);
  }
}

}  // namespace follow_bot
