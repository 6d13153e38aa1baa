// The parker's AprilTag target: one configured tag id, its pose from the camera intrinsics.
//
// Detection uses Debian's libapriltag (C) directly rather than ViSP's vpDetectorAprilTag: ViSP
// 3.5 wraps the same detector but does not expose the decision margin, so it cannot gate weak
// decodes (false positives on texture). The C detector reports decision_margin and hamming per
// detection, reads the cv::Mat in place (no vpImage copy) and is configured like ViSP's (one
// thread, same quad decimation), so on a near tag it costs no more than a bare
// vpDetectorAprilTag::detect (make bench measures both on the same frames).
//
// The quad search on a decimated image is fast but loses small and foreshortened tags and fits
// their corners coarsely (real frames: 17 of 27 tags found; 1.9 mm off on a 0.5 m one). What it
// misses is searched again at full resolution over the frame; a quad it finds with a side below
// `full_resolution_below` is fitted again at full resolution on the patch around it only.
//
// Raw frames through a lens (CameraGeometry::lens): the quad found on the raw frame is searched
// again on the rectified camera's image of the patch around it (refitRectified), where the
// tag's edges are straight; its corners are then the rectified camera's pixels.
//
// Pose: OpenCV's IPPE for a square gives both local minima of the planar pose problem (the tilt
// ambiguity; Debian's libapriltag does not export its orthogonal-iteration solver). The one with
// the smaller reprojection residual wins, then Gauss-Newton refines it on the corners;
// when the two residuals are within `ambiguity_ratio` of each other or both below corner noise
// (`ambiguity_px`: a far, face-on tag, where tilt is unobservable) the one closer in rotation to
// the previous frame's pose is kept, so the pose never flips sign from frame to frame.
// On the same corners this agrees with ViSP's VVS and orthogonal iteration to 0.01 mm (its
// real AprilTag photo): the pose error there came from the corners, not the estimator.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "follow_bot/ParkerDefaults.h"
#include "follow_bot/common.h"
#include "follow_bot/marker_target.h"
#include "follow_bot_common/config_fields.h"

namespace follow_bot {

struct TagDetectorConfig {
  // The parker's ~tag_* defaults (cfg/Parker.cfg).
  std::string family = ParkerDefaults::tag_family;  // tag36h11, tag25h9, tag16h5, ...
  int id = ParkerDefaults::tag_id;                  // only this id is accepted
  double size_m = ParkerDefaults::tag_size;         // edge of the black square, metres
  // Quad search on a 1/decimate image; corners refined at full resolution.
  double quad_decimate = ParkerDefaults::quad_decimate;
  // With quad_decimate > 1: a quad found there whose shortest side is below this (pixels) is
  // fitted again at full resolution on the patch around it; none found, the whole frame is
  // searched again at full resolution.
  double full_resolution_below = ParkerDefaults::full_resolution_below;
  // Below this a decode is treated as a false positive.
  double min_decision_margin = ParkerDefaults::min_decision_margin;
  int max_hamming = ParkerDefaults::max_hamming;  // corrected bits accepted (0: exact codes only)
  // The two pose solutions count as equally good (keep the previous frame's branch) when their
  // reprojection residuals are within this ratio, or both below ambiguity_px (corner noise).
  double ambiguity_ratio = 1.5;
  double ambiguity_px = 0.2;

  static constexpr auto fields() {
    using C = TagDetectorConfig;
    return std::make_tuple(
        cfgField("family", &C::family, {}, "tag_family"),
        cfgField("id", &C::id, inRange(0, 1e6), "tag_id"),
        cfgField("size_m", &C::size_m, positive(), "tag_size"),
        cfgField("quad_decimate", &C::quad_decimate, inRange(1.0, 8.0)),
        cfgField("full_resolution_below", &C::full_resolution_below, atLeast(0.0)),
        cfgField("min_decision_margin", &C::min_decision_margin, inRange(0.0, 255.0)),
        cfgField("max_hamming", &C::max_hamming, inRange(0, 3)),
        field("ambiguity_ratio", &C::ambiguity_ratio, atLeast(1.0)),
        field("ambiguity_px", &C::ambiguity_px, atLeast(0.0)));
  }
};

// Empty when usable, otherwise a message naming the first bad field.
std::string validate(const TagDetectorConfig& config);

// The size of the image libapriltag 3.3 runs its quad search on (image_u8_decimate: 1.5 is a
// special 2/3 scale, any other decimate > 1 its integer part, 1 + (n - 1) / factor pixels).
cv::Size quadSearchSize(cv::Size image, double quad_decimate);
// apriltag_quad_thresh reads outside a quad-search image with fewer rows than this, or no
// column, and crashes (SIGSEGV); detect() returns no tag for such frames instead.
constexpr int kMinQuadSearchRows = 3;

class TagDetector : public MarkerDetector {
 public:
  // Throws std::invalid_argument for an invalid config or an unknown family.
  explicit TagDetector(const TagDetectorConfig& config);
  ~TagDetector() override;
  TagDetector(const TagDetector&) = delete;
  TagDetector& operator=(const TagDetector&) = delete;

  std::optional<MarkerObservation> detect(const cv::Mat& gray,
                                          const CameraGeometry& camera) override;
  // Forgets the previous pose (the ambiguity tie-break starts afresh).
  void reset();
  const TagDetectorConfig& config() const { return config_; }

 private:
  struct Quad {
    std::vector<cv::Point2d> corners;  // apriltag's order (BL, BR, TR, TL), OpenCV pixel centres
    double decision_margin = 0;
  };
  // The configured tag's best accepted detection in `gray` with the quad search on a
  // 1/quad_decimate image, or none.
  std::optional<Quad> findQuad(const cv::Mat& gray, double quad_decimate) const;
  // The configured tag in `gray` at quad_decimate, again at full resolution where that found
  // none or a small quad (full_resolution_below).
  std::optional<Quad> locateQuad(const cv::Mat& gray) const;
  // The quad found again on the rectified camera's image of the patch around `corners`
  // (rectified pixels) of the raw frame `raw`, or none when it is not found there.
  std::optional<std::vector<cv::Point2d>> refitRectified(const cv::Mat& raw,
                                                         const CameraGeometry& camera,
                                                         const std::vector<cv::Point2d>& corners);

  struct Impl;
  TagDetectorConfig config_;
  std::unique_ptr<Impl> impl_;
  std::optional<cv::Matx33d> previous_rotation_;
  RectifiedPatches patches_;  // through a lens: the rectified patches refitRectified searches
};

}  // namespace follow_bot
