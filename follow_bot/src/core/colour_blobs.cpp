#include "follow_bot/colour_blobs.h"

#include <algorithm>
#include <cmath>
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
           requireInRange("roundness_tolerance", config.roundness_tolerance, 0.0, 1.0),
       }) {
    if (!error.empty()) return error;
  }
  if (const auto& ball = config.floor_ball) {
    for (const std::string& error : {
             requirePositive("floor_ball.radius_m", ball->radius_m),
             requireInRange("floor_ball.tolerance", ball->tolerance, 0.0, 1.0),
         }) {
      if (!error.empty()) return error;
    }
    if (const std::string error = validate(ball->camera); !error.empty()) {
      return "floor_ball.camera: " + error;
    }
  }
  return "";
}

std::optional<CircleFit> fitCircle(const std::vector<cv::Point>& contour, cv::Size image) {
  // x^2 + y^2 + D x + E y + F = 0 in the least-squares sense: linear in (D, E, F).
  std::vector<cv::Point2d> arc;
  for (const cv::Point& p : contour) {
    if (p.x > 0 && p.y > 0 && p.x < image.width - 1 && p.y < image.height - 1) arc.push_back(p);
  }
  constexpr std::size_t kMinPoints = 5;
  if (arc.size() < kMinPoints) return std::nullopt;
  cv::Mat a(static_cast<int>(arc.size()), 3, CV_64F);
  cv::Mat b(static_cast<int>(arc.size()), 1, CV_64F);
  for (int i = 0; i < a.rows; ++i) {
    const cv::Point2d& p = arc[i];
    a.at<double>(i, 0) = p.x;
    a.at<double>(i, 1) = p.y;
    a.at<double>(i, 2) = 1.0;
    b.at<double>(i) = -(p.x * p.x + p.y * p.y);
  }
  const cv::SVD svd(a);
  // Rank < 3: the pixels lie on one line, which fits no circle.
  if (svd.w.at<double>(2) <= 1e-9 * svd.w.at<double>(0)) return std::nullopt;
  cv::Mat def;
  svd.backSubst(b, def);
  CircleFit fit;
  fit.centre = {-def.at<double>(0) / 2.0, -def.at<double>(1) / 2.0};
  const double radius_squared = fit.centre.dot(fit.centre) - def.at<double>(2);
  if (!(radius_squared > 0.0) || !std::isfinite(radius_squared)) return std::nullopt;
  fit.radius = std::sqrt(radius_squared);
  double sum_squared = 0.0;
  for (const cv::Point2d& p : arc) {
    const double error = cv::norm(p - fit.centre) - fit.radius;
    sum_squared += error * error;
  }
  fit.rms_error = std::sqrt(sum_squared / static_cast<double>(arc.size()));
  return fit;
}

std::optional<double> floorBallRadius(const CameraGeometry& camera, const cv::Point2d& centre,
                                      double radius_px) {
  if (!(radius_px > 0.0) || !std::isfinite(centre.x) || !std::isfinite(centre.y)) {
    return std::nullopt;
  }
  // The circle's ends on the line from the principal point through its centre (any line when
  // the centre is the principal point), as rays of the rectified camera (x right, y down, z
  // along the optical axis).
  const cv::Point2d principal(camera.cx, camera.cy);
  cv::Point2d along = centre - principal;
  const double offset = cv::norm(along);
  along = offset > 1e-9 ? along / offset : cv::Point2d(0.0, 1.0);
  const auto ray = [&](const cv::Point2d& raw) {
    const cv::Point2d p = rectifyPixel(camera, raw);
    return cv::normalize(
        cv::Vec3d((p.x - camera.cx) / camera.fx, (p.y - camera.cy) / camera.fy, 1.0));
  };
  const cv::Vec3d near = ray(centre - radius_px * along);
  const cv::Vec3d far = ray(centre + radius_px * along);
  const double alpha = 0.5 * std::acos(std::clamp(near.dot(far), -1.0, 1.0));
  const cv::Vec3d axis = cv::normalize(near + far);
  const double sin_theta =
      axis[1] * std::cos(camera.pitch_rad) + axis[2] * std::sin(camera.pitch_rad);
  const double denominator = 1.0 + sin_theta / std::sin(alpha);
  if (!(alpha > 0.0) || !(denominator > 0.0)) return std::nullopt;
  const double radius = camera.height_m / denominator;
  return std::isfinite(radius) ? std::optional<double>(radius) : std::nullopt;
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
      if (area < config_.min_area || !beaconShaped(contour, bgr.size())) continue;
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

bool ColourBlobDetector::beaconShaped(const std::vector<cv::Point>& contour, cv::Size image) const {
  const bool round_gate = config_.roundness_tolerance > 0.0;
  if (!round_gate && !config_.floor_ball) return true;
  const std::optional<CircleFit> fit = fitCircle(contour, image);
  if (!fit) return true;
  constexpr double kQuantisationPx = 1.0;
  if (round_gate && fit->rms_error > kQuantisationPx + config_.roundness_tolerance * fit->radius) {
    return false;
  }
  if (!config_.floor_ball) return true;
  const ColourBlobConfig::FloorBall& ball = *config_.floor_ball;
  // Boundary pixel centres lie half a pixel inside the silhouette's edge.
  const std::optional<double> radius = floorBallRadius(ball.camera, fit->centre, fit->radius + 0.5);
  return radius && std::abs(*radius - ball.radius_m) <= ball.tolerance * ball.radius_m;
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
