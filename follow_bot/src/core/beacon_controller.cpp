#include "follow_bot/beacon_controller.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "follow_bot/common.h"
#include "follow_bot/path_geometry.h"
#include "follow_bot_common/config_checks.h"

namespace follow_bot {
namespace {

std::string prefixed(const char* prefix, const std::string& error) {
  return error.empty() ? error : prefix + error;
}

std::string requireName(const char* name, const std::string& value) {
  return value.empty() ? std::string(name) + " must not be empty" : "";
}

// The blob of a colour when it is found, else nullptr.
const ColourBlob* seen(const BlobResult& blobs, const std::string& name) {
  const ColourBlob* blob = blobs.find(name);
  if (blob == nullptr || !blob->found) return nullptr;
  if (!std::isfinite(blob->centroid.x) || !std::isfinite(blob->centroid.y)) return nullptr;
  return blob;
}

}  // namespace

std::string validate(const BeaconObject& object) {
  for (const std::string& error :
       {requirePositive("size_m", object.size_m), requirePositive("depth_m", object.depth_m)}) {
    if (!error.empty()) return error;
  }
  return "";
}

std::optional<double> rangeFromWidth(double focal_px, double width_m, double width_px) {
  if (!(focal_px > 0.0) || !(width_m > 0.0) || !(width_px > 0.0)) return std::nullopt;
  const double range = focal_px * width_m / width_px;
  if (!std::isfinite(range)) return std::nullopt;
  return range;
}

std::optional<cv::Point3d> sphereCentreFromCircle(const CameraGeometry& camera,
                                                  const cv::Point2d& circle_centre,
                                                  double circle_radius_px, double radius_m) {
  if (!(radius_m > 0.0) || !(circle_radius_px > 0.0) || !isFinite(circle_centre) ||
      !validate(camera).empty()) {
    return std::nullopt;
  }
  // Normalised image coordinates; the circle's ends on the line through the principal point
  // are c - a and c + a from it.
  const double x = (circle_centre.x - camera.cx) / camera.fx;
  const double y = (circle_centre.y - camera.cy) / camera.fy;
  const double c = std::hypot(x, y);
  const double a = circle_radius_px / std::sqrt(camera.fx * camera.fy);
  const double near_edge = std::atan(c - a);
  const double far_edge = std::atan(c + a);
  const double alpha = 0.5 * (far_edge - near_edge);  // angular radius
  const double theta = 0.5 * (far_edge + near_edge);  // angle of the centre off the axis
  if (!(alpha > 0.0)) return std::nullopt;
  const double distance = radius_m / std::sin(alpha);
  const double phi = std::atan2(y, x);
  // The centre in the optical frame (x right, y down, z forward) ...
  const double right = distance * std::sin(theta) * std::cos(phi);
  const double down = distance * std::sin(theta) * std::sin(phi);
  const double forward = distance * std::cos(theta);
  // ... and in base_link (axes as in ground_projection.h).
  const double sin_p = std::sin(camera.pitch_rad);
  const double cos_p = std::cos(camera.pitch_rad);
  const cv::Point3d centre(camera.x_offset_m + forward * cos_p - down * sin_p, -right,
                           camera.height_m - forward * sin_p - down * cos_p);
  if (!std::isfinite(centre.x) || !std::isfinite(centre.y) || !std::isfinite(centre.z)) {
    return std::nullopt;
  }
  return centre;
}

RectifiedBlob rectifyBlob(const ColourBlob& blob, const CameraGeometry& camera,
                          const cv::Size& frame_size) {
  RectifiedBlob rectified;
  const std::vector<cv::Point2d> raw(blob.contour.begin(), blob.contour.end());
  rectified.contour = rectifyPixels(camera, raw);
  if (!camera.lens) {
    rectified.area = rectified.area_in_frame = blob.area;
    rectified.centroid = blob.centroid;
    rectified.circle_centre = blob.circle_centre;
    rectified.circle_radius = blob.circle_radius;
    rectified.width = blob.bounding_box.width;
    return rectified;
  }
  if (rectified.contour.empty()) return rectified;
  // contourArea, moments and the hull take float points.
  const std::vector<cv::Point2f> contour(rectified.contour.begin(), rectified.contour.end());
  rectified.area = cv::contourArea(contour);
  const cv::Moments moments = cv::moments(contour);
  // Clamping a contour of points a pixel apart to the frame cuts it at the frame's edges to
  // within a fraction of a pixel.
  std::vector<cv::Point2f> inside_frame;
  inside_frame.reserve(contour.size());
  for (const cv::Point2f& point : contour) {
    inside_frame.emplace_back(std::clamp(point.x, 0.0f, frame_size.width - 1.0f),
                              std::clamp(point.y, 0.0f, frame_size.height - 1.0f));
  }
  rectified.area_in_frame = cv::contourArea(inside_frame);
  cv::Point2f centre;
  float radius = 0.0f;
  std::vector<cv::Point2f> hull;
  cv::convexHull(contour, hull);
  cv::minEnclosingCircle(hull, centre, radius);
  rectified.circle_centre = centre;
  rectified.circle_radius = radius;
  // As the detector: a zero-area contour has no moment centroid.
  rectified.centroid = moments.m00 > 0.0
                           ? cv::Point2d(moments.m10 / moments.m00, moments.m01 / moments.m00)
                           : rectified.circle_centre;
  const auto [left, right] =
      std::minmax_element(rectified.contour.begin(), rectified.contour.end(),
                          [](const cv::Point2d& a, const cv::Point2d& b) { return a.x < b.x; });
  rectified.width = right->x - left->x + 1.0;
  return rectified;
}

std::optional<cv::Point3d> sphereCentre(const ColourBlob& blob, int image_width, int image_height,
                                        const CameraGeometry& camera, double radius_m) {
  const cv::Rect& box = blob.bounding_box;
  if (!blob.found || box.x <= 0 || box.y <= 0 || box.x + box.width >= image_width ||
      box.y + box.height >= image_height) {
    return std::nullopt;
  }
  const RectifiedBlob rectified = rectifyBlob(blob, camera, cv::Size(image_width, image_height));
  return sphereCentreFromCircle(camera, rectified.circle_centre, rectified.circle_radius, radius_m);
}

RangeEstimate estimateRange(const ColourBlob& blob, int image_width, int image_height,
                            const CameraGeometry& camera, const BeaconObject& object) {
  RangeEstimate estimate;
  if (!blob.found || !(object.size_m > 0.0)) return estimate;
  if (object.shape == BeaconShape::kSphere) {
    const std::optional<cv::Point3d> centre =
        sphereCentre(blob, image_width, image_height, camera, object.size_m);
    if (centre)
      estimate.from_size = std::max(0.0, std::hypot(centre->x, centre->y) - object.size_m);
    return estimate;
  }
  // Cut by the frame's edges: the raw box against the raw frame.
  const cv::Rect& box = blob.bounding_box;
  const RectifiedBlob rectified = rectifyBlob(blob, camera, cv::Size(image_width, image_height));
  const bool cut_left = box.x <= 0;
  const bool cut_right = box.x + box.width >= image_width;
  const bool cut_bottom = box.y + box.height >= image_height;
  if (!cut_left && !cut_right) {
    const std::optional<double> depth = rangeFromWidth(camera.fx, object.size_m, rectified.width);
    if (depth) estimate.from_size = std::max(0.0, *depth + camera.x_offset_m);
  }
  if (!cut_bottom) {
    for (const cv::Point2d& pixel : rectified.contour) {
      const std::optional<cv::Point2d> floor = pixelToGround(camera, pixel.x, pixel.y);
      if (!floor) continue;
      const double range = std::hypot(floor->x, floor->y);
      if (!estimate.from_ground || range < *estimate.from_ground) estimate.from_ground = range;
    }
  }
  return estimate;
}

std::optional<BoxFace> boxFace(const ColourBlob& blob, int image_width, int image_height,
                               const CameraGeometry& camera) {
  const cv::Rect& box = blob.bounding_box;
  if (!blob.found || box.y + box.height >= image_height || box.width <= 0 ||
      box.x + box.width > image_width) {
    return std::nullopt;
  }
  // The lowest outline pixel of each column, where the silhouette meets the floor.
  std::vector<int> lowest_row(box.width, -1);
  for (const cv::Point& pixel : blob.contour) {
    if (pixel.x < box.x || pixel.x >= box.x + box.width) continue;  // not the blob's own
    int& row = lowest_row[pixel.x - box.x];
    row = std::max(row, pixel.y);
  }
  std::vector<cv::Point2d> lowest;
  for (int i = 0; i < box.width; ++i) {
    if (lowest_row[i] >= 0) lowest.emplace_back(box.x + i, lowest_row[i]);
  }
  std::vector<cv::Point2f> floor;
  double nearest = std::numeric_limits<double>::infinity();
  for (const cv::Point2d& pixel : rectifyPixels(camera, lowest)) {
    if (const std::optional<cv::Point2d> point = pixelToGround(camera, pixel.x, pixel.y)) {
      floor.emplace_back(*point);
      nearest = std::min(nearest, std::hypot(point->x, point->y));
    }
  }
  // Contacts twice as far as the nearest are not the face's: things behind it, or the lowest
  // pixels of columns only a leaning side edge crosses (a pitched camera's verticals lean).
  // Left in, they would sway the first fit.
  floor.erase(std::remove_if(
                  floor.begin(), floor.end(),
                  [nearest](const cv::Point2f& p) { return std::hypot(p.x, p.y) > 2.0 * nearest; }),
              floor.end());
  constexpr std::size_t kMinContacts = 10;
  cv::Vec4f face;
  const auto on_face = [&face](const std::vector<cv::Point2f>& points) {
    std::vector<cv::Point2f> kept;
    for (const cv::Point2f& p : points) {
      const double off = std::abs((p.x - face[2]) * face[1] - (p.y - face[3]) * face[0]);
      if (off <= std::max(0.05, 0.05 * std::hypot(p.x, p.y))) kept.push_back(p);
    }
    return kept;
  };
  if (floor.size() < kMinContacts) return std::nullopt;
  cv::fitLine(floor, face, cv::DIST_HUBER, 0.0, 0.01, 0.01);
  std::vector<cv::Point2f> contacts = on_face(floor);
  if (contacts.size() < kMinContacts) return std::nullopt;
  cv::fitLine(contacts, face, cv::DIST_HUBER, 0.0, 0.01, 0.01);
  contacts = on_face(contacts);
  if (contacts.size() < kMinContacts) return std::nullopt;
  BoxFace found;
  found.along = cv::Point2d(face[0], face[1]);
  if (found.along.y > 0.0) found.along = -found.along;  // base_link y falls to the right
  const cv::Point2d origin(face[2], face[3]);
  found.foot = origin - origin.dot(found.along) * found.along;
  found.eye = cv::Point2d(camera.x_offset_m, 0.0);
  const auto [leftmost, rightmost] = std::minmax_element(
      contacts.begin(), contacts.end(), [&found](const cv::Point2f& a, const cv::Point2f& b) {
        return cv::Point2d(a).dot(found.along) < cv::Point2d(b).dot(found.along);
      });
  found.leftmost = *leftmost;
  found.rightmost = *rightmost;
  if (!isFinite(found.foot) || found.foot.dot(found.foot) == 0.0) return std::nullopt;
  return found;
}

namespace {

// Where the ray through `contact` meets the face, seen from above.
std::optional<cv::Point2d> faceEnd(const BoxFace& face, const cv::Point2d& contact) {
  const cv::Point2d ray = contact - face.eye;
  const double crossing = ray.cross(face.along);
  if (std::abs(crossing) < 1e-9) return std::nullopt;
  return face.eye + ((face.foot - face.eye).cross(face.along) / crossing) * ray;
}

}  // namespace

std::optional<cv::Point2d> boxCentre(const BoxFace& face, bool cut_left, bool cut_right,
                                     const BeaconObject& object) {
  if (object.shape != BeaconShape::kBox || (cut_left && cut_right)) return std::nullopt;
  std::optional<cv::Point2d> middle;  // of the face
  if (!cut_left && !cut_right) {
    const std::optional<cv::Point2d> left = faceEnd(face, face.leftmost);
    const std::optional<cv::Point2d> right = faceEnd(face, face.rightmost);
    if (!left || !right) return std::nullopt;
    const cv::Point2d span = *right - *left;
    if (std::abs(std::hypot(span.x, span.y) - object.size_m) > 0.15 * object.size_m) {
      return std::nullopt;
    }
    middle = 0.5 * (*left + *right);
  } else if (!cut_left) {
    middle = faceEnd(face, face.leftmost);
    if (middle) *middle += 0.5 * object.size_m * face.along;
  } else {
    middle = faceEnd(face, face.rightmost);
    if (middle) *middle -= 0.5 * object.size_m * face.along;
  }
  if (!middle) return std::nullopt;
  const cv::Point2d centre = *middle + 0.5 * object.depth_m * face.behind();
  if (!isFinite(centre)) return std::nullopt;
  return centre;
}

std::string validate(const BeaconControllerConfig& c) {
  for (const std::string& error : {
           checkFields(c),
           requireName("follow_colour", c.follow_colour),
           requireName("stop_colour", c.stop_colour),
           c.follow_colour == c.stop_colour && !c.follow_colour.empty()
               ? "follow_colour and stop_colour must differ, both are '" + c.follow_colour + "'"
               : "",
           requireName("target_colour", c.target_colour),
           prefixed("target.", validate(c.target)),
           prefixed("camera.", validate(c.camera)),
           requireAtLeast("distance_release", c.distance_release, c.distance_tolerance),
           requireAtLeast("bearing_release", c.bearing_release, c.bearing_tolerance),
       }) {
    if (!error.empty()) return error;
  }
  return "";
}

std::string checkColoursDetected(const BeaconControllerConfig& controller,
                                 const ColourBlobConfig& detector) {
  std::vector<std::pair<const char*, std::string>> used;
  if (controller.mode == BeaconMode::kFollowGreenStopRed) {
    used = {{"follow_colour", controller.follow_colour}, {"stop_colour", controller.stop_colour}};
  } else {
    used = {{"target_colour", controller.target_colour}};
  }
  for (const auto& [field, colour] : used) {
    const std::string& name = colour;  // a lambda may not capture a structured binding (C++17)
    const bool detected = std::any_of(detector.colours.begin(), detector.colours.end(),
                                      [&](const ColourSpec& spec) { return spec.name == name; });
    if (!detected) {
      return std::string(field) + " '" + name + "' is not one of the detector's colours";
    }
  }
  return "";
}

BeaconController::BeaconController(const BeaconControllerConfig& config) : config_(config) {
  const std::string error = validate(config);
  if (!error.empty()) throw std::invalid_argument("BeaconController: " + error);
}

void BeaconController::reset() { *this = BeaconController(config_); }

Twist2D BeaconController::update(const BlobResult& blobs, double stamp) {
  if (!std::isfinite(stamp) || !blobs.ok()) return Twist2D();
  if (has_stamp_ && stamp < last_stamp_) reset();
  has_stamp_ = true;
  last_stamp_ = stamp;

  const Twist2D command = config_.mode == BeaconMode::kFollowGreenStopRed
                              ? followGreenStopRed(blobs, stamp)
                              : approach(blobs, stamp);
  if (!std::isfinite(command.linear) || !std::isfinite(command.angular)) return Twist2D();
  return command;
}

Twist2D BeaconController::followGreenStopRed(const BlobResult& blobs, double stamp) {
  const cv::Size frame(blobs.image_width, blobs.image_height);
  const ColourBlob* stop = seen(blobs, config_.stop_colour);
  if (stop != nullptr && rectifyBlob(*stop, config_.camera, frame).area >= config_.stop_min_area) {
    stop_seen_ = true;
    stop_last_seen_ = stamp;
  }
  if (stop_seen_ && stamp - stop_last_seen_ <= config_.stop_release_delay) {
    state_ = BeaconState::kStoppedByRed;
    return Twist2D();
  }

  const ColourBlob* found = seen(blobs, config_.follow_colour);
  if (found == nullptr || blobs.image_width <= 0) return search();
  const RectifiedBlob target = rectifyBlob(*found, config_.camera, frame);
  const double half_width = 0.5 * blobs.image_width;
  const double error = std::clamp((target.centroid.x - half_width) / half_width, -1.0, 1.0);
  if (error != 0.0) search_direction_ = error > 0.0 ? -1.0 : 1.0;
  // The distance left as a fraction of the hold distance: a sphere's silhouette area falls as
  // the square of its distance.
  const double distance_left = std::sqrt(config_.close_area / target.area_in_frame) - 1.0;
  if (target.area_in_frame >= config_.close_area ||
      (state_ == BeaconState::kHolding && distance_left <= config_.hold_release)) {
    state_ = BeaconState::kHolding;
    return Twist2D();
  }
  state_ = BeaconState::kApproaching;
  const double speed =
      distance_left >= config_.approach_taper
          ? config_.approach_speed
          : std::clamp(config_.approach_speed * distance_left / config_.approach_taper,
                       std::min(config_.creep_speed, config_.approach_speed),
                       config_.approach_speed);
  return Twist2D{speed, -config_.turn_gain * error};
}

Twist2D BeaconController::approach(const BlobResult& blobs, double stamp) {
  const ColourBlob* target = seen(blobs, config_.target_colour);
  if (target == nullptr) {
    last_range_.reset();
    last_bearing_.reset();
    aimed_at_.reset();
    if (target_seen_ && stamp - target_last_seen_ <= config_.lost_hold) {
      state_ = BeaconState::kLost;
      return Twist2D();
    }
    return search();
  }
  target_seen_ = true;
  target_last_seen_ = stamp;

  const CameraGeometry& camera = config_.camera;
  const cv::Rect& box = target->bounding_box;
  const bool cut_left = box.x <= 0;
  const bool cut_right = box.x + box.width >= blobs.image_width;
  const cv::Point2d aim =
      config_.target.shape == BeaconShape::kBox
          ? cv::Point2d(box.x + 0.5 * (box.width - 1),  // middle of the silhouette
                        box.y + 0.5 * (box.height - 1))
          : target->centroid;
  const double column = rectifyPixel(camera, aim).x;  // a raw frame's through the lens
  const std::optional<BoxFace> face =
      config_.target.shape == BeaconShape::kBox
          ? boxFace(*target, blobs.image_width, blobs.image_height, camera)
          : std::nullopt;
  const std::optional<cv::Point2d> centre =
      face ? boxCentre(*face, cut_left, cut_right, config_.target) : std::nullopt;
  const std::optional<double> range =
      estimateRange(*target, blobs.image_width, blobs.image_height, camera, config_.target).best();
  // The point aimed at, in base_link: carried by the commands sent since the last frame (a late
  // base makes them all in the end), then the box's centre where one is placed, else as far
  // along the column's bearing as the range. A box spilling over both sides places none and
  // the carried point stands. One end in view places the centre from the face's direction,
  // whose row-quantised fit (+-0.5 deg at 2 m) swings it ~1 cm across over 0.9 m of face:
  // such a centre moves the carried point only 0.15 of the way, so that the last one before
  // the face fills the view cannot turn the robot by its error.
  if (aimed_at_) {
    const double dt = stamp - last_command_stamp_;
    const Pose2D moved{arcDisplacement(last_command_.linear * dt, last_command_.angular * dt),
                       last_command_.angular * dt};
    aimed_at_ = seenFrom({*aimed_at_}, moved).front();
  }
  constexpr double kOneEndWeight = 0.15;
  if (centre) {
    const cv::Point2d placed = centre.value();
    if (aimed_at_ && cut_left != cut_right) {
      aimed_at_ = *aimed_at_ + kOneEndWeight * (placed - *aimed_at_);
    } else {
      aimed_at_ = placed;
    }
  } else if (!(cut_left && cut_right)) {
    const double angle = -std::atan((column - camera.cx) / camera.fx);  // to the left
    aimed_at_ =
        range.value_or(config_.stop_distance) * cv::Point2d(std::cos(angle), std::sin(angle));
  }
  // Positive to the right, as the column's.
  const double bearing = aimed_at_ ? -std::atan2(aimed_at_->y, aimed_at_->x) : 0.0;
  if (bearing != 0.0) search_direction_ = bearing > 0.0 ? -1.0 : 1.0;
  last_range_ = range;
  last_bearing_ = bearing;

  const bool arrived = state_ == BeaconState::kArrived;
  const double distance_bound = arrived ? config_.distance_release : config_.distance_tolerance;
  const double bearing_bound = arrived ? config_.bearing_release : config_.bearing_tolerance;
  Twist2D command;
  if (range && std::abs(*range - config_.stop_distance) < distance_bound &&
      std::abs(bearing) < bearing_bound) {
    state_ = BeaconState::kArrived;
  } else {
    state_ = BeaconState::kApproaching;
    if (range) {
      const double min_speed = config_.allow_reverse ? -config_.max_linear : 0.0;
      const double taper = std::max(0.0, 1.0 - std::abs(bearing) / config_.speed_taper_bearing);
      command.linear = taper * std::clamp(config_.k_range * (*range - config_.stop_distance),
                                          min_speed, config_.max_linear);
    }
    // A turn of less than 1e-4 rad (0.006 deg) is not worth a command: a bearing carried
    // through a face that fills the view only ever tends to zero.
    constexpr double kLeastBearing = 1e-4;
    command.angular =
        std::abs(bearing) < kLeastBearing
            ? 0.0
            : std::clamp(-config_.k_bearing * bearing, -config_.max_angular, config_.max_angular);
  }
  last_command_ = command;
  last_command_stamp_ = stamp;
  return command;
}

Twist2D BeaconController::search() {
  state_ = BeaconState::kSearching;
  return Twist2D{0.0, search_direction_ * config_.search_rate};
}

}  // namespace follow_bot
