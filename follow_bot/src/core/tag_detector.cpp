#include "follow_bot/tag_detector.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

extern "C" {
#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagCircle21h7.h>
#include <apriltag/tagStandard41h12.h>
}

#include "follow_bot/common.h"
#include "follow_bot_common/config_checks.h"

namespace follow_bot {

namespace {

struct FamilyFactory {
  const char* name;
  apriltag_family_t* (*create)();
  void (*destroy)(apriltag_family_t*);
};

const FamilyFactory kFamilies[] = {
    {"tag36h11", tag36h11_create, tag36h11_destroy},
    {"tag25h9", tag25h9_create, tag25h9_destroy},
    {"tag16h5", tag16h5_create, tag16h5_destroy},
    {"tagCircle21h7", tagCircle21h7_create, tagCircle21h7_destroy},
    {"tagStandard41h12", tagStandard41h12_create, tagStandard41h12_destroy},
};

const FamilyFactory* findFamily(const std::string& name) {
  for (const FamilyFactory& family : kFamilies) {
    if (name == family.name) return &family;
  }
  return nullptr;
}

// Where libapriltag puts a pixel's centre, in its own coordinates (quad_decimate's and
// refine_edges' `+ 0.5`).
constexpr double kApriltagPixelCentre = 0.5;

// The pixels around a quad, with a margin of a quarter of its size: the white border apriltag
// needs around the black square, and room for the corners to move when fitted again.
cv::Rect2d patchAround(const std::vector<cv::Point2d>& corners) {
  cv::Point2d low = corners.front(), high = corners.front();
  for (const cv::Point2d& corner : corners) {
    low = {std::min(low.x, corner.x), std::min(low.y, corner.y)};
    high = {std::max(high.x, corner.x), std::max(high.y, corner.y)};
  }
  const double margin = 0.25 * std::max(high.x - low.x, high.y - low.y) + 2.0;
  return {low - cv::Point2d(margin, margin), high + cv::Point2d(margin, margin)};
}

double shortestSide(const std::vector<cv::Point2d>& corners) {
  double shortest = cv::norm(corners.back() - corners.front());
  for (std::size_t i = 1; i < corners.size(); ++i) {
    shortest = std::min(shortest, cv::norm(corners[i] - corners[i - 1]));
  }
  return shortest;
}

// Angle of the rotation taking a to b, radians.
double rotationAngle(const cv::Matx33d& a, const cv::Matx33d& b) {
  const cv::Matx33d delta = a.t() * b;
  const double cosine = (cv::trace(delta) - 1.0) / 2.0;
  return std::acos(std::max(-1.0, std::min(1.0, cosine)));
}

struct PoseCandidate {
  cv::Matx33d rotation;
  cv::Vec3d translation;
  double rms_px = 0;
};

// Reprojection RMS of `object` under (rotation, translation), pixels.
double reprojectionRms(const std::vector<cv::Point3d>& object,
                       const std::vector<cv::Point2d>& image, const CameraGeometry& camera,
                       const cv::Matx33d& rotation, const cv::Vec3d& translation) {
  double sum = 0;
  for (std::size_t i = 0; i < object.size(); ++i) {
    const cv::Vec3d p = rotation * cv::Vec3d(object[i]) + translation;
    sum += std::pow(camera.fx * p[0] / p[2] + camera.cx - image[i].x, 2) +
           std::pow(camera.fy * p[1] / p[2] + camera.cy - image[i].y, 2);
  }
  return std::sqrt(sum / object.size());
}

// Gauss-Newton on the corners' reprojection error from a close start (IPPE's). A fixed 6x6
// solve with the analytic Jacobian: cv::solvePnPRefineLM does the same for 4 points at ~20x the
// cost of its generic machinery, which alone would break the bench's 10 % pose budget.
void refinePose(const std::vector<cv::Point3d>& object, const std::vector<cv::Point2d>& image,
                const CameraGeometry& camera, cv::Matx33d& rotation, cv::Vec3d& translation) {
  for (int iteration = 0; iteration < 5; ++iteration) {
    cv::Matx66d normal = cv::Matx66d::zeros();
    cv::Vec6d gradient;
    for (std::size_t i = 0; i < object.size(); ++i) {
      const cv::Vec3d rotated = rotation * cv::Vec3d(object[i]);
      const cv::Vec3d p = rotated + translation;
      const double iz = 1.0 / p[2];
      const double residual[2] = {camera.fx * p[0] * iz + camera.cx - image[i].x,
                                  camera.fy * p[1] * iz + camera.cy - image[i].y};
      // d(u, v)/dp, and dp/d(omega, t) = [-[rotated]x, I] for R <- exp([omega]x) R, t <- t + dt.
      const cv::Matx23d dpixel(camera.fx * iz, 0, -camera.fx * p[0] * iz * iz,  //
                               0, camera.fy * iz, -camera.fy * p[1] * iz * iz);
      const cv::Matx33d skew(0, -rotated[2], rotated[1], rotated[2], 0, -rotated[0], -rotated[1],
                             rotated[0], 0);
      const cv::Matx23d by_rotation = dpixel * (-skew);
      for (int row = 0; row < 2; ++row) {
        const cv::Vec6d j(by_rotation(row, 0), by_rotation(row, 1), by_rotation(row, 2),
                          dpixel(row, 0), dpixel(row, 1), dpixel(row, 2));
        normal += j * j.t();
        gradient += j * residual[row];
      }
    }
    cv::Vec6d step;
    if (!cv::solve(normal, -gradient, step, cv::DECOMP_CHOLESKY)) return;
    cv::Matx33d delta;
    cv::Rodrigues(cv::Vec3d(step[0], step[1], step[2]), delta);
    rotation = delta * rotation;
    translation += cv::Vec3d(step[3], step[4], step[5]);
  }
}

}  // namespace

std::string validate(const TagDetectorConfig& config) {
  if (!findFamily(config.family)) {
    std::string names;
    for (const FamilyFactory& family : kFamilies) names += std::string(" ") + family.name;
    return "family must be one of" + names + ", got '" + config.family + "'";
  }
  return checkFields(config);
}

struct TagDetector::Impl {
  const FamilyFactory* factory = nullptr;
  apriltag_family_t* family = nullptr;
  apriltag_detector_t* detector = nullptr;

  ~Impl() {
    if (detector) apriltag_detector_destroy(detector);
    if (family) factory->destroy(family);
  }
};

TagDetector::TagDetector(const TagDetectorConfig& config)
    : config_(config), impl_(std::make_unique<Impl>()) {
  const std::string error = validate(config);
  if (!error.empty()) throw std::invalid_argument(error);
  impl_->factory = findFamily(config.family);
  impl_->family = impl_->factory->create();
  if (config.id >= static_cast<int>(impl_->family->ncodes)) {
    throw std::invalid_argument("id must be < " + std::to_string(impl_->family->ncodes) + " for " +
                                config.family + ", got " + std::to_string(config.id));
  }
  impl_->detector = apriltag_detector_create();
  // The decode table only holds codes up to max_hamming bits away: nothing further can match.
  apriltag_detector_add_family_bits(impl_->detector, impl_->family, config.max_hamming);
  // ViSP's defaults, so the bench compares like with like: one thread, no blur, refined edges.
  impl_->detector->nthreads = 1;
  impl_->detector->quad_sigma = 0.0f;
  impl_->detector->refine_edges = true;
  impl_->detector->decode_sharpening = 0.25;
}

TagDetector::~TagDetector() = default;

void TagDetector::reset() { previous_rotation_.reset(); }

cv::Size quadSearchSize(cv::Size image, double quad_decimate) {
  if (quad_decimate == 1.5) return {image.width / 3 * 2, image.height / 3 * 2};
  const int factor = static_cast<int>(quad_decimate);
  if (factor <= 1) return image;
  return {1 + (image.width - 1) / factor, 1 + (image.height - 1) / factor};
}

std::optional<TagDetector::Quad> TagDetector::findQuad(const cv::Mat& gray,
                                                       double quad_decimate) const {
  const cv::Size searched = quadSearchSize(gray.size(), quad_decimate);
  if (searched.height < kMinQuadSearchRows || searched.width < 1) return std::nullopt;
  // apriltag reads the pixels in place; it never writes to its input image.
  image_u8_t image{gray.cols, gray.rows, static_cast<int32_t>(gray.step[0]),
                   const_cast<uint8_t*>(gray.ptr<uint8_t>())};
  impl_->detector->quad_decimate = static_cast<float>(quad_decimate);
  zarray_t* detections = apriltag_detector_detect(impl_->detector, &image);
  const apriltag_detection_t* best = nullptr;
  for (int i = 0; i < zarray_size(detections); ++i) {
    apriltag_detection_t* det = nullptr;
    zarray_get(detections, i, &det);
    if (det->id != config_.id || det->hamming > config_.max_hamming ||
        det->decision_margin < config_.min_decision_margin) {
      continue;
    }
    if (!best || det->decision_margin > best->decision_margin) best = det;
  }
  std::optional<Quad> quad;
  if (best) {
    quad = Quad{};
    quad->decision_margin = best->decision_margin;
    // apriltag's pixel centres are at half-integer coordinates (pixel (0, 0) spans [0, 1]), ours
    // and the intrinsics' at integers (OpenCV, ROS CameraInfo, ViSP).
    for (const auto& corner : best->p) {
      quad->corners.emplace_back(corner[0] - kApriltagPixelCentre,
                                 corner[1] - kApriltagPixelCentre);
    }
  }
  apriltag_detections_destroy(detections);
  return quad;
}

std::optional<TagDetector::Quad> TagDetector::locateQuad(const cv::Mat& gray) const {
  std::optional<Quad> quad = findQuad(gray, config_.quad_decimate);
  if (config_.quad_decimate <= 1.0) return quad;
  // The decimated search loses small and foreshortened tags (their cells fall below its pixels)
  // and fits their corners coarsely: the frame is searched again at full resolution when nothing
  // was found, and a small quad fitted again at full resolution on the patch around it.
  if (!quad) return findQuad(gray, 1.0);
  if (shortestSide(quad->corners) >= config_.full_resolution_below) return quad;
  const cv::Rect patch =
      cv::Rect(patchAround(quad->corners)) & cv::Rect(0, 0, gray.cols, gray.rows);
  std::optional<Quad> refitted = findQuad(gray(patch), 1.0);
  if (!refitted) return quad;
  for (cv::Point2d& corner : refitted->corners) corner += cv::Point2d(patch.tl());
  return refitted;
}

std::optional<std::vector<cv::Point2d>> TagDetector::refitRectified(
    const cv::Mat& raw, const CameraGeometry& camera, const std::vector<cv::Point2d>& corners) {
  // The rectified camera's pixels around the quad.
  const cv::Rect2d patch_bounds = patchAround(corners);
  // A quad far larger than the frame or far outside it is no real tag (a lens that folds the
  // image over); its patch would cost more than the frame.
  const cv::Rect2d near_frame(-raw.cols, -raw.rows, 3.0 * raw.cols, 3.0 * raw.rows);
  if ((patch_bounds & near_frame) != patch_bounds) return std::nullopt;
  const cv::Rect patch_rect(static_cast<int>(std::floor(patch_bounds.x)),
                            static_cast<int>(std::floor(patch_bounds.y)),
                            static_cast<int>(std::ceil(patch_bounds.width)),
                            static_cast<int>(std::ceil(patch_bounds.height)));
  std::optional<Quad> quad = locateQuad(patches_.patch(raw, camera, patch_rect));
  if (!quad) return std::nullopt;
  for (cv::Point2d& corner : quad->corners) corner += cv::Point2d(patch_rect.tl());
  return quad->corners;
}

std::optional<MarkerObservation> TagDetector::detect(const cv::Mat& gray,
                                                     const CameraGeometry& camera) {
  if (gray.empty() || gray.type() != CV_8UC1 || !validate(camera).empty()) return std::nullopt;
  std::optional<Quad> quad = locateQuad(gray);
  if (!quad) return std::nullopt;
  // The pose is the rectified camera's: corners of a raw frame go through the lens first. A
  // barrel lens bows the tag's straight edges in the raw frame and apriltag fits straight lines
  // to them, so their corners land beyond the true ones (through the harness's turtlebot3 lens
  // the tag looks 9 mm nearer at the parker's 0.5 m standoff): the quad is fitted again on the
  // rectified image of the patch around it, where its edges are straight.
  std::vector<cv::Point2d> image = rectifyPixels(camera, quad->corners);
  if (!std::all_of(image.begin(), image.end(),
                   [](const cv::Point2d& p) { return std::isfinite(p.x) && std::isfinite(p.y); })) {
    return std::nullopt;
  }
  if (camera.lens) {
    if (std::optional<std::vector<cv::Point2d>> refitted = refitRectified(gray, camera, image)) {
      image = *refitted;
    }
  }
  std::optional<MarkerObservation> out = MarkerObservation{};
  out->id = config_.id;
  out->quality = quad->decision_margin;
  for (int i = 0; i < 4; ++i) out->corners[i] = image[3 - i];  // apriltag wraps BL, BR, TR, TL

  // Both minima of the planar pose problem (IPPE for a square, object points in apriltag's
  // corner order), then the chosen one refined on the four corners (refinePose).
  const double h = config_.size_m / 2.0;
  const std::vector<cv::Point3d> object = {{-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}};
  const cv::Matx33d k(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  std::vector<cv::Mat> rvecs, tvecs;
  std::vector<double> residuals;
  cv::solvePnPGeneric(object, image, k, cv::noArray(), rvecs, tvecs, false,
                      cv::SOLVEPNP_IPPE_SQUARE, cv::noArray(), cv::noArray(), residuals);
  std::vector<PoseCandidate> candidates;
  for (std::size_t s = 0; s < rvecs.size() && s < residuals.size(); ++s) {
    PoseCandidate candidate;
    cv::Rodrigues(rvecs[s], candidate.rotation);
    candidate.translation = cv::Vec3d(tvecs[s]);
    candidate.rms_px = residuals[s];
    if (candidate.translation[2] > 0 && std::isfinite(candidate.rms_px)) {
      candidates.push_back(candidate);
    }
  }
  if (candidates.empty()) {
    out.reset();
  } else {
    std::size_t pick = 0;
    if (candidates.size() == 2) {
      const double low = std::min(candidates[0].rms_px, candidates[1].rms_px);
      const double high = std::max(candidates[0].rms_px, candidates[1].rms_px);
      const bool ambiguous = high <= config_.ambiguity_ratio * low || high <= config_.ambiguity_px;
      if (ambiguous && previous_rotation_) {
        pick = rotationAngle(*previous_rotation_, candidates[1].rotation) <
                       rotationAngle(*previous_rotation_, candidates[0].rotation)
                   ? 1
                   : 0;
      } else {
        pick = candidates[1].rms_px < candidates[0].rms_px ? 1 : 0;
      }
    }
    out->rotation = candidates[pick].rotation;
    out->translation = candidates[pick].translation;
    refinePose(object, image, camera, out->rotation, out->translation);
    out->reprojection_error_px =
        reprojectionRms(object, image, camera, out->rotation, out->translation);
    previous_rotation_ = out->rotation;
  }
  return out;
}

}  // namespace follow_bot
