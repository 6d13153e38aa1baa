// Finds a known textured sign (a reference picture of known physical width) in camera images and
// measures its pose: SIFT features of the reference, matched with Lowe's ratio test, a RANSAC
// homography with an inlier minimum, refined by aligning the image (ECC's model, solved in
// doubles) to a rendering of the reference under that homography (keypoints alone are good to
// ~0.3 px, too coarse for the tilt and depth of a far sign), then the planar pose from the
// refined homography and the sign's metric size (IPPE, both solutions, LM-refined).
//
// After a detection the sign is tracked instead of searched for: corners inside it in the last
// frame are followed into the new frame (pyramidal Lucas-Kanade), a RANSAC homography through
// them starts the same render-and-align passes, which must all succeed. Every pose is aligned to
// the reference picture, never to the last frame, so tracking does not drift; when it fails
// (too few corners, a mirrored or jumping outline, an alignment that fails) the frame falls back
// to the SIFT search.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "follow_bot/ParkerDefaults.h"
#include "follow_bot/common.h"
#include "follow_bot/marker_target.h"
#include "follow_bot_common/config_fields.h"

namespace follow_bot {

struct SignDetectorConfig {
  // Reference picture of the sign's face, read as grey levels (the parker's ~sign_image).
  std::string image_path = ParkerDefaults::sign_image;
  // Physical width of that picture (~sign_width); its height follows the aspect ratio.
  double width_m = ParkerDefaults::sign_width;
  double ratio = 0.75;   // Lowe's ratio: best match distance / second best must be below it
  int min_inliers = 15;  // RANSAC inliers needed to accept a detection
  double ransac_threshold_px = 3.0;        // reprojection distance that makes a RANSAC inlier
  int max_reference_features = 3000;       // strongest reference keypoints kept (0 = all)
  int min_reference_features = 50;         // fewer makes the reference featureless: startup error
  int max_image_features = 0;              // strongest keypoints kept per camera image (0 = all)
  double max_reprojection_error_px = 2.0;  // RMS over the inliers of the final pose, else rejected
  int refine_passes = 2;             // render-and-align passes before the pose; 0 = keypoints only
  int refine_iterations = 30;        // alignment step limit per pass (it stops once converged)
  double min_correlation = 0.8;      // correlation needed to use the refined homography
  double max_refine_shift_px = 3.0;  // larger corner moves mean it diverged: keep RANSAC's
  // When the two planar-pose solutions' RMS errors differ by less than this (pixels), they cannot
  // be told apart reliably and the one nearest the previous frame's pose is kept.
  double ambiguity_px = 0.05;
  bool track = true;                  // follow the sign between frames; false = search every frame
  int track_features = 50;            // corners inside the sign followed into the next frame
  int track_window_px = 21;           // side of the Lucas-Kanade window (odd)
  int track_levels = 3;               // pyramid levels above full resolution
  double max_track_motion_px = 80.0;  // a corner of the sign moving further: lost, search again
  // A tracked frame starts the alignment within a fraction of a pixel, so it needs fewer passes
  // and steps than a searched one (the alignment is much of a frame's cost).
  int track_refine_passes = 1;      // render-and-align passes on a tracked frame, all required
  int track_refine_iterations = 5;  // alignment step limit per pass on a tracked frame

  static constexpr auto fields() {
    using C = SignDetectorConfig;
    return std::make_tuple(
        cfgField("image_path", &C::image_path, {}, "sign_image"),
        cfgField("width_m", &C::width_m, positive(), "sign_width"),
        field("ratio", &C::ratio, inRange(0.1, 1.0)),
        field("min_inliers", &C::min_inliers, atLeast(4)),
        field("ransac_threshold_px", &C::ransac_threshold_px, positive()),
        field("max_reference_features", &C::max_reference_features, atLeast(0)),
        field("min_reference_features", &C::min_reference_features, atLeast(4)),
        field("max_image_features", &C::max_image_features, atLeast(0)),
        field("max_reprojection_error_px", &C::max_reprojection_error_px, positive()),
        field("refine_passes", &C::refine_passes, atLeast(0)),
        field("refine_iterations", &C::refine_iterations, atLeast(1)),
        field("min_correlation", &C::min_correlation, inRange(0.0, 1.0)),
        field("max_refine_shift_px", &C::max_refine_shift_px, positive()),
        field("ambiguity_px", &C::ambiguity_px, atLeast(0.0)), field("track", &C::track),
        field("track_features", &C::track_features),
        field("track_window_px", &C::track_window_px, atLeast(5)),
        field("track_levels", &C::track_levels, atLeast(0)),
        field("max_track_motion_px", &C::max_track_motion_px, positive()),
        field("track_refine_passes", &C::track_refine_passes, atLeast(1)),
        field("track_refine_iterations", &C::track_refine_iterations, atLeast(1)));
  }
};

// Empty when the configuration is usable (the image itself is checked by the constructor),
// otherwise a message naming the first bad field.
std::string validate(const SignDetectorConfig& config);

class SignDetector : public MarkerDetector {
 public:
  // Reads the reference and computes its features once. Throws std::invalid_argument when the
  // configuration is invalid, the image is missing or unreadable, or it has too few features.
  explicit SignDetector(const SignDetectorConfig& config);

  // The sign in a mono8 image (id 0, quality = inlier count), or nothing. Remembers the pose it
  // returns to settle the planar ambiguity of the next frame, and the frame to track from; a
  // frame of another size starts afresh.
  std::optional<MarkerObservation> detect(const cv::Mat& gray,
                                          const CameraGeometry& camera) override;

  // Forget the previous pose and sighting (e.g. after the sign was lost for a while): the next
  // frame is searched whole.
  void reset();

  // Whether the last detect() followed the sign from the frame before (false: searched, or
  // nothing found).
  bool lastTracked() const { return last_tracked_; }

  int referenceFeatures() const { return static_cast<int>(reference_points_.size()); }
  double heightMetres() const { return height_m_; }

 private:
  struct Matches {
    cv::Matx33d plane_to_image;       // RANSAC homography, sign plane (metres) to raw pixels
    std::vector<cv::Point3f> object;  // inliers on the sign plane
    std::vector<cv::Point2f> image;   // ... and in the image
  };
  // SIFT keypoints inside `window` (optionally found on a half-resolution copy), matched and
  // RANSAC-filtered; nothing below min_inliers or for a mirrored fit.
  std::optional<Matches> matchIn(const cv::Mat& gray, const cv::Rect& window,
                                 bool half_resolution) const;
  // Corners inside the sign in the last frame followed into `gray`, RANSAC-filtered; nothing
  // below min_inliers, for a mirrored fit or when a sign corner moved beyond max_track_motion_px.
  std::optional<Matches> trackInto(const cv::Mat& gray) const;
  // RANSAC homography through plane-to-image correspondences, its inliers; nothing below
  // min_inliers or when the sign would appear mirrored.
  std::optional<Matches> fitHomography(const std::vector<cv::Point3f>& object,
                                       const std::vector<cv::Point2f>& image) const;
  // The pose from matches: the homography aligned (refine_passes; for `tracked` matches
  // track_refine_passes, every one required), IPPE, the reprojection gate. On success remembers the
  // pose, the aligned homography and where to search next.
  std::optional<MarkerObservation> poseFrom(const cv::Mat& gray, const CameraGeometry& camera,
                                            const Matches& matches, bool tracked);
  // The sign's corners TL, TR, BR, BL on its plane, metres.
  std::vector<cv::Point2d> outlinePlane() const;
  // One render-and-align pass of at most `iterations` steps on a sign-plane (metres) to
  // rectified-pixel homography, in place (through a lens, on the rectified patch of the raw
  // frame); false (and the homography untouched) when the alignment fails, correlates poorly or
  // moves the corners too far.
  bool refineHomography(const cv::Mat& gray, const CameraGeometry& camera, int iterations,
                        cv::Matx33d& plane_to_image);

  SignDetectorConfig config_;
  double height_m_ = 0.0;
  std::vector<cv::Mat> textures_;  // the picture in float grey levels, then ever narrower copies
  cv::Ptr<cv::SIFT> sift_;
  cv::BFMatcher matcher_{cv::NORM_L2};
  std::vector<cv::Point3f> reference_points_;  // keypoints on the sign plane, metres, z = 0
  cv::Mat reference_descriptors_;
  std::optional<cv::Matx33d> previous_rotation_;
  std::optional<cv::Rect> search_window_;  // where the sign was last seen, grown
  bool search_half_resolution_ = false;    // it was big there
  cv::Mat last_frame_;                     // the last frame the sign was found in (tracking)
  cv::Matx33d last_plane_to_image_;        // ... and its aligned homography there (raw pixels)
  cv::Size frame_size_;                    // size of the frames seen since the last reset
  bool last_tracked_ = false;
  RectifiedPatches patches_;  // through a lens: the rectified views the alignment works on
};

}  // namespace follow_bot
