#include "follow_bot/tag_detector.h"

#include <cmath>
#include <functional>
#include <stdexcept>
#include <vector>

#include <opencv2/calib3d.hpp>

extern "C" {
#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagCircle21h7.h>
#include <apriltag/tagStandard41h12.h>
}

#include "follow_bot/config_checks.h"

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

}  // namespace

std::string validate(const TagDetectorConfig& config) {
  if (!findFamily(config.family)) {
    std::string names;
    for (const FamilyFactory& family : kFamilies) names += std::string(" ") + family.name;
    return "family must be one of" + names + ", got '" + config.family + "'";
  }
  for (const std::string& error : {
           requireInRange("id", config.id, 0, 1e6),
           requirePositive("size_m", config.size_m),
           requireInRange("quad_decimate", config.quad_decimate, 1.0, 8.0),
           requireInRange("min_decision_margin", config.min_decision_margin, 0.0, 255.0),
           requireInRange("max_hamming", config.max_hamming, 0, 3),
           requireAtLeast("ambiguity_ratio", config.ambiguity_ratio, 1.0),
           requireAtLeast("ambiguity_px", config.ambiguity_px, 0.0),
       }) {
    if (!error.empty()) return error;
  }
  return "";
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
  impl_->detector->quad_decimate = static_cast<float>(config.quad_decimate);
  impl_->detector->quad_sigma = 0.0f;
  impl_->detector->refine_edges = true;
  impl_->detector->decode_sharpening = 0.25;
}

TagDetector::~TagDetector() = default;

void TagDetector::reset() { previous_rotation_.reset(); }

std::optional<MarkerObservation> TagDetector::detect(const cv::Mat& gray,
                                                     const CameraGeometry& camera) {
  if (gray.empty() || gray.type() != CV_8UC1 || !validate(camera).empty()) return std::nullopt;
  // apriltag reads the pixels in place; it never writes to its input image.
  image_u8_t image{gray.cols, gray.rows, static_cast<int32_t>(gray.step[0]),
                   const_cast<uint8_t*>(gray.ptr<uint8_t>())};
  zarray_t* detections = apriltag_detector_detect(impl_->detector, &image);
  apriltag_detection_t* best = nullptr;
  for (int i = 0; i < zarray_size(detections); ++i) {
    apriltag_detection_t* det = nullptr;
    zarray_get(detections, i, &det);
    if (det->id != config_.id || det->hamming > config_.max_hamming ||
        det->decision_margin < config_.min_decision_margin) {
      continue;
    }
    if (!best || det->decision_margin > best->decision_margin) best = det;
  }
  std::optional<MarkerObservation> out;
  if (best) {
    out = MarkerObservation{};
    out->id = best->id;
    out->quality = best->decision_margin;
    for (int i = 0; i < 4; ++i) {  // apriltag wraps BL, BR, TR, TL; we report TL, TR, BR, BL
      out->corners[i] = cv::Point2d(best->p[3 - i][0], best->p[3 - i][1]);
    }

    // Both minima of the planar pose problem (IPPE for a square), each refined by
    // Levenberg-Marquardt on the four corners; object points in apriltag's corner order.
    const double h = config_.size_m / 2.0;
    const std::vector<cv::Point3d> object = {{-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}};
    std::vector<cv::Point2d> image;
    for (int i = 0; i < 4; ++i) image.emplace_back(best->p[i][0], best->p[i][1]);
    const cv::Matx33d k(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
    std::vector<cv::Mat> rvecs, tvecs;
    cv::solvePnPGeneric(object, image, k, cv::noArray(), rvecs, tvecs, false,
                        cv::SOLVEPNP_IPPE_SQUARE);
    std::vector<PoseCandidate> candidates;
    for (std::size_t s = 0; s < rvecs.size(); ++s) {
      cv::solvePnPRefineLM(object, image, k, cv::noArray(), rvecs[s], tvecs[s]);
      PoseCandidate candidate;
      cv::Rodrigues(rvecs[s], candidate.rotation);
      candidate.translation = cv::Vec3d(tvecs[s]);
      std::vector<cv::Point2d> projected;
      cv::projectPoints(object, rvecs[s], tvecs[s], k, cv::noArray(), projected);
      double sum = 0;
      for (int i = 0; i < 4; ++i) sum += std::pow(cv::norm(projected[i] - image[i]), 2);
      candidate.rms_px = std::sqrt(sum / 4.0);
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
        const bool ambiguous =
            high <= config_.ambiguity_ratio * low || high <= config_.ambiguity_px;
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
      out->reprojection_error_px = candidates[pick].rms_px;
      previous_rotation_ = out->rotation;
    }
  }
  apriltag_detections_destroy(detections);
  return out;
}

}  // namespace follow_bot
