#include "follow_bot/sign_detector.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "follow_bot/common.h"
#include "follow_bot_common/config_checks.h"
#include "image_converter/feature_matching.h"

namespace follow_bot {
namespace {

// OpenCV's SIFT doubles the image with a resize that puts source pixel x at 2x + 0.5, but scales
// keypoints back by a plain halving, so every keypoint comes out a quarter pixel right of and
// below its true position (measured: +0.24 px on a blob of known centre). Undo it so poses are
// unbiased.
constexpr float kSiftOffsetPx = 0.25f;

// Pixels along the sign's outline left out of the alignment.
constexpr int kEdgeBandPx = 4;

// Larger signs are aligned on a block-averaged copy no wider or taller than this.
constexpr int kAlignMaxPx = 100;

// The rendering samples the narrowest of a ladder of reduced copies of the picture at least as
// wide as it needs, widths apart by this factor (at most this much finer than needed: no
// aliasing), built once instead of a reduction per alignment.
constexpr double kTextureStep = 1.189207115002721;  // 2^(1/4)
constexpr int kMinTextureCols = 16;

// The alignment stops when a step moves no corner of the sign by this much (view pixels).
constexpr double kAlignEpsilonPx = 1e-2;
// Fraction of the Gauss-Newton step taken: whole steps overshot the far sign's tilt nearly
// twofold, and it oscillated around the optimum instead of converging (measured on the
// fronto-parallel sweep: +-0.025 px at the corners after 30 steps; with half steps they
// settle below 0.01 px within 6).
constexpr double kAlignStep = 0.5;

// A sign last seen larger than this (its smaller side, pixels) is searched at half resolution.
constexpr int kHalfResolutionSignPx = 150;

// Extra pixels around the last sighting searched first in the next frame.
constexpr int kSearchMarginPx = 64;

// Corners followed between frames (Shi-Tomasi): minimum eigenvalue relative to the strongest,
// and spacing, so they spread over the sign.
constexpr double kTrackCornerQuality = 0.01;
constexpr double kTrackCornerSpacingPx = 5.0;
// Corners are found on a block-averaged copy of a sign bigger than this (pixels).
constexpr int kCornersMaxPx = 200;
// Lucas-Kanade stops after this many iterations or a step below this many pixels.
constexpr int kTrackIterations = 30;
constexpr double kTrackEpsilonPx = 0.01;

std::vector<cv::Point2f> keypointPositions(const std::vector<cv::KeyPoint>& keypoints) {
  std::vector<cv::Point2f> points;
  points.reserve(keypoints.size());
  for (const cv::KeyPoint& k : keypoints) {
    points.emplace_back(k.pt.x - kSiftOffsetPx, k.pt.y - kSiftOffsetPx);
  }
  return points;
}

double rotationAngle(const cv::Matx33d& a, const cv::Matx33d& b) {
  const cv::Matx33d relative = a.t() * b;
  const double c = (cv::trace(relative) - 1.0) / 2.0;
  return std::acos(std::clamp(c, -1.0, 1.0));
}

// Signed area of a polygon in pixels; positive when its vertices run clockwise on screen (image
// y points down), which is how TL, TR, BR, BL of a sign seen from the front run.
double signedArea(const std::vector<cv::Point2f>& polygon) {
  double area = 0.0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const cv::Point2f& p = polygon[i];
    const cv::Point2f& q = polygon[(i + 1) % polygon.size()];
    area += static_cast<double>(p.x) * q.y - static_cast<double>(q.x) * p.y;
  }
  return area / 2.0;
}

// Grey levels in double precision, smoothed by the 5x5 Gaussian that lets an alignment reach
// from a pixel or two away.
cv::Mat smoothed(const cv::Mat& gray) {
  cv::Mat image;
  gray.convertTo(image, CV_64F);
  cv::GaussianBlur(image, image, cv::Size(5, 5), 0, 0);
  return image;
}

// One Gauss-Newton step of the alignment of `camera` to `rendering` (both smoothed, same size)
// over the pixels of `mask`: the homography S, view pixel to rendering pixel near the identity,
// for which camera(p) = a rendering(S p) + b best, the gain a and offset b solved with it. Sets
// `correlation` to the two images' correlation coefficient before the step; nothing when the
// images do not correlate. cv::findTransformECC solves the same step in single precision on
// raw pixel coordinates, where the tilt terms (scale x^2 ~ 1e4) make its 8 x 8 system too
// ill-conditioned for floats: face-on from afar the tilt came out different with every SIMD
// instruction set. Coordinates centred and scaled to [-1, 1], in doubles, it is well posed.
std::optional<cv::Matx33d> alignmentStep(const cv::Mat& camera, const cv::Mat& rendering,
                                         const cv::Mat& mask, double& correlation) {
  constexpr int kUnknowns = 10;  // a, b, a times the 8 homography terms
  const double cx = (rendering.cols - 1) / 2.0;
  const double cy = (rendering.rows - 1) / 2.0;
  const double scale = std::max(rendering.cols, rendering.rows) / 2.0;
  cv::Matx<double, kUnknowns, kUnknowns> normal = cv::Matx<double, kUnknowns, kUnknowns>::zeros();
  cv::Matx<double, kUnknowns, 1> projected = cv::Matx<double, kUnknowns, 1>::zeros();
  double n = 0, sum_c = 0, sum_r = 0, sum_cc = 0, sum_rr = 0, sum_cr = 0;
  for (int v = 1; v + 1 < rendering.rows; ++v) {
    const double* r = rendering.ptr<double>(v);
    const double* above = rendering.ptr<double>(v - 1);
    const double* below = rendering.ptr<double>(v + 1);
    const double* c = camera.ptr<double>(v);
    const unsigned char* m = mask.ptr<unsigned char>(v);
    const double y = (v - cy) / scale;
    for (int u = 1; u + 1 < rendering.cols; ++u) {
      if (!m[u]) continue;
      const double x = (u - cx) / scale;
      // Gradient per unit of the scaled coordinates.
      const double gx = (r[u + 1] - r[u - 1]) / 2.0 * scale;
      const double gy = (below[u] - above[u]) / 2.0 * scale;
      const double perspective = -(gx * x + gy * y);
      const double row[kUnknowns] = {r[u],   1.0,    gx * x, gx * y,          gx,
                                     gy * x, gy * y, gy,     perspective * x, perspective * y};
      for (int i = 0; i < kUnknowns; ++i) {
        for (int j = i; j < kUnknowns; ++j) normal(i, j) += row[i] * row[j];
        projected(i) += row[i] * c[u];
      }
      n += 1.0;
      sum_c += c[u];
      sum_r += r[u];
      sum_cc += c[u] * c[u];
      sum_rr += r[u] * r[u];
      sum_cr += c[u] * r[u];
    }
  }
  const double var_c = sum_cc - sum_c * sum_c / n;
  const double var_r = sum_rr - sum_r * sum_r / n;
  if (!(n >= kUnknowns && var_c > 0.0 && var_r > 0.0)) return std::nullopt;
  correlation = (sum_cr - sum_c * sum_r / n) / std::sqrt(var_c * var_r);
  for (int i = 0; i < kUnknowns; ++i) {
    for (int j = 0; j < i; ++j) normal(i, j) = normal(j, i);
  }
  cv::Matx<double, kUnknowns, 1> solution;
  if (!cv::solve(normal, projected, solution, cv::DECOMP_CHOLESKY)) return std::nullopt;
  const double gain = solution(0);
  if (!(gain > 0.0)) return std::nullopt;
  // camera(p) = a rendering(p) + b + a grad . d(p): the terms of d are solution / a.
  const cv::Matx<double, kUnknowns, 1> d = solution * (kAlignStep / gain);
  const cv::Matx33d scaled(1.0 + d(2), d(3), d(4), d(5), 1.0 + d(6), d(7), d(8), d(9), 1.0);
  const cv::Matx33d to_scaled(1.0 / scale, 0.0, -cx / scale, 0.0, 1.0 / scale, -cy / scale, 0.0,
                              0.0, 1.0);
  return to_scaled.inv() * scaled * to_scaled;
}

}  // namespace

std::string validate(const SignDetectorConfig& config) {
  if (config.image_path.empty()) return "image_path must name the sign's reference picture";
  for (const std::string& error : {
           checkFields(config),
           requireAtLeast("track_features", config.track_features, config.min_inliers),
       }) {
    if (!error.empty()) return error;
  }
  return "";
}

SignDetector::SignDetector(const SignDetectorConfig& config) : config_(config) {
  const std::string error = validate(config);
  if (!error.empty()) throw std::invalid_argument("sign detector: " + error);
  const cv::Mat reference = cv::imread(config.image_path, cv::IMREAD_GRAYSCALE);
  if (reference.empty()) {
    throw std::invalid_argument("sign detector: cannot read the sign image '" + config.image_path +
                                "' (missing or not an image)");
  }
  std::vector<cv::KeyPoint> keypoints;
  cv::SIFT::create(config.max_reference_features)
      ->detectAndCompute(reference, cv::noArray(), keypoints, reference_descriptors_);
  if (static_cast<int>(keypoints.size()) < config.min_reference_features) {
    std::ostringstream message;
    message << "sign detector: the sign image '" << config.image_path
            << "' is featureless: " << keypoints.size() << " SIFT keypoints, need at least "
            << config.min_reference_features;
    throw std::invalid_argument(message.str());
  }
  // Reference pixel (u, v), centres at integers, to the sign plane: origin at the picture's
  // centre, x right, y down, metres.
  const double metres_per_px = config.width_m / reference.cols;
  height_m_ = metres_per_px * reference.rows;
  for (const cv::Point2f& p : keypointPositions(keypoints)) {
    reference_points_.emplace_back((p.x + 0.5) * metres_per_px - config.width_m / 2.0,
                                   (p.y + 0.5) * metres_per_px - height_m_ / 2.0, 0.0f);
  }
  sift_ = cv::SIFT::create(config.max_image_features);
  // Rendered in floats: grey levels rounded to integers change with every small change of the
  // homography, which kept the alignment's steps from settling below kAlignEpsilonPx (a tracked
  // frame of the overload test's probe: 3.3 ms CPU rendered in integers, 2.3 in floats).
  cv::Mat picture;
  reference.convertTo(picture, CV_32F);
  for (double cols = picture.cols; cols >= kMinTextureCols; cols /= kTextureStep) {
    const int c = static_cast<int>(std::lround(cols));
    const int rows =
        std::max(kMinTextureCols, static_cast<int>(std::lround(c * height_m_ / config.width_m)));
    cv::Mat level = picture;
    if (c < picture.cols) cv::resize(picture, level, cv::Size(c, rows), 0, 0, cv::INTER_AREA);
    textures_.push_back(level);
  }
}

bool SignDetector::refineHomography(const cv::Mat& gray, const CameraGeometry& camera,
                                    int iterations, cv::Matx33d& plane_to_image) {
  // Render the sign as the camera would see it under the current homography (area-sampled like
  // a sensor pixel), then align the camera image to that rendering. Aligning against a picture
  // with the same perspective and blur everywhere is what makes the refinement unbiased: a
  // fronto-parallel template biased oblique and far signs by up to 0.7 % of their range.
  const std::vector<cv::Point2d> outline = outlinePlane();
  std::vector<cv::Point2d> before;
  cv::perspectiveTransform(outline, before, plane_to_image);
  cv::Rect roi = cv::boundingRect(std::vector<cv::Point2f>(before.begin(), before.end())) &
                 cv::Rect(0, 0, gray.cols, gray.rows);
  // A big sign is aligned on a block-averaged copy: its pose is well conditioned anyway, and
  // the alignment's cost grows with the pixel count.
  const int f = std::max(1, static_cast<int>(std::ceil(std::max(roi.width, roi.height) /
                                                       static_cast<double>(kAlignMaxPx))));
  roi.width -= roi.width % f;
  roi.height -= roi.height % f;
  const cv::Size size(roi.width / f, roi.height / f);
  if (size.width < 16 || size.height < 16) return false;
  // Through a lens, the rectified camera's view: a homography cannot follow the raw frame's
  // bent edges (aligned on raw frames, signs at 1-2 m came out ~6 mm off).
  cv::Mat camera_view = camera.lens ? patches_.patch(gray, camera, roi) : gray(roi);
  if (f > 1) cv::resize(camera_view, camera_view, size, 0, 0, cv::INTER_AREA);
  // Image pixel p to aligned pixel (p - roi + 0.5) / f - 0.5 (pixel centres at integers).
  const double inv_f = 1.0 / f;
  const cv::Matx33d image_to_view(inv_f, 0.0, (0.5 - roi.x) * inv_f - 0.5, 0.0, inv_f,
                                  (0.5 - roi.y) * inv_f - 0.5, 0.0, 0.0, 1.0);
  cv::Matx33d plane_to_view = image_to_view * plane_to_image;

  const double area = static_cast<double>(size.width) * size.height;
  const int ss = area <= 40000 ? 4 : area <= 160000 ? 2 : 1;  // supersampling of the rendering
  // Source texture hardly finer than the supersampled view, so bilinear sampling does not alias.
  const double width_px = (cv::norm(before[1] - before[0]) + cv::norm(before[2] - before[3])) / 2;
  const double cols = width_px * inv_f * ss;
  const auto coarser = std::find_if(textures_.rbegin(), textures_.rend(),
                                    [&](const cv::Mat& level) { return level.cols >= cols; });
  const cv::Mat& texture = coarser == textures_.rend() ? textures_.front() : *coarser;
  // Texture texel (u, v), centres at integers, to the sign plane; view pixel to the fine grid
  // (fine sample k sits at view pixel (k + 0.5) / ss - 0.5).
  const double mx = config_.width_m / texture.cols;
  const double my = height_m_ / texture.rows;
  const cv::Matx33d texel_to_plane(mx, 0.0, 0.5 * mx - config_.width_m / 2, 0.0, my,
                                   0.5 * my - height_m_ / 2, 0.0, 0.0, 1.0);
  const cv::Matx33d view_to_fine(ss, 0.0, (ss - 1) / 2.0, 0.0, ss, (ss - 1) / 2.0, 0.0, 0.0, 1.0);
  // Only pixels well inside the sign count: within kEdgeBandPx of its outline the camera sees
  // the sign blended with an unknown background (blurred further by the 5x5 smoothing).
  std::vector<cv::Point2d> outline_view;
  cv::perspectiveTransform(outline, outline_view, plane_to_view);
  std::vector<cv::Point> polygon;
  polygon.reserve(outline_view.size());
  for (const cv::Point2d& p : outline_view)
    polygon.emplace_back(cvRound(p.x * 16), cvRound(p.y * 16));
  cv::Mat mask = cv::Mat::zeros(size, CV_8UC1);
  cv::fillConvexPoly(mask, polygon, cv::Scalar(255), cv::LINE_8, 4);
  const cv::Size band(2 * kEdgeBandPx + 1, 2 * kEdgeBandPx + 1);
  cv::erode(mask, mask, cv::getStructuringElement(cv::MORPH_ELLIPSE, band));

  const cv::Mat camera_smooth = smoothed(camera_view);
  double correlation = 0.0;
  for (int i = 0; i < iterations; ++i) {
    cv::Mat fine, rendered;
    cv::warpPerspective(texture, fine, cv::Mat(view_to_fine * plane_to_view * texel_to_plane),
                        size * ss, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
    cv::resize(fine, rendered, size, 0, 0, cv::INTER_AREA);
    // view_to_rendering: rendering(S p) = camera(p), and the rendering shows the picture through
    // the current homography, so the camera sees it through S^-1 of it.
    const std::optional<cv::Matx33d> view_to_rendering =
        alignmentStep(camera_smooth, smoothed(rendered), mask, correlation);
    if (!view_to_rendering) return false;
    plane_to_view = view_to_rendering->inv() * plane_to_view;
    plane_to_view *= 1.0 / plane_to_view(2, 2);
    std::vector<cv::Point2d> corners_after;
    cv::perspectiveTransform(outline_view, corners_after, *view_to_rendering);
    double moved = 0.0;
    for (size_t k = 0; k < corners_after.size(); ++k) {
      moved = std::max(moved, cv::norm(corners_after[k] - outline_view[k]));
    }
    if (moved < kAlignEpsilonPx) break;
  }
  if (!(correlation >= config_.min_correlation)) return false;
  cv::Matx33d refined = image_to_view.inv() * plane_to_view;
  refined *= 1.0 / refined(2, 2);
  std::vector<cv::Point2d> after;
  cv::perspectiveTransform(outline, after, refined);
  for (size_t i = 0; i < after.size(); ++i) {
    if (!(cv::norm(after[i] - before[i]) <= config_.max_refine_shift_px)) return false;
  }
  plane_to_image = refined;
  return true;
}

std::optional<SignDetector::Matches> SignDetector::matchIn(const cv::Mat& gray,
                                                           const cv::Rect& window,
                                                           bool half_resolution) const {
  cv::Mat searched = gray(window);
  if (half_resolution) {
    cv::resize(searched, searched, cv::Size(window.width / 2, window.height / 2), 0, 0,
               cv::INTER_AREA);
  }
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  sift_->detectAndCompute(searched, cv::noArray(), keypoints, descriptors);
  if (static_cast<int>(keypoints.size()) < config_.min_inliers) return std::nullopt;

  std::vector<cv::Point2f> window_positions = keypointPositions(keypoints);
  if (half_resolution) {  // half-resolution pixel q covers full pixels 2q and 2q + 1
    for (cv::Point2f& p : window_positions) p = p * 2.0f + cv::Point2f(0.5f, 0.5f);
  }
  const cv::Point2f offset(static_cast<float>(window.x), static_cast<float>(window.y));
  std::vector<cv::Point3f> object_points;
  std::vector<cv::Point2f> image_points;
  for (const cv::DMatch& match : image_converter::ratioTestMatches(
           matcher_, descriptors, reference_descriptors_, config_.ratio)) {
    object_points.push_back(reference_points_[match.trainIdx]);
    image_points.push_back(window_positions[match.queryIdx] + offset);
  }
  return fitHomography(object_points, image_points);
}

std::optional<SignDetector::Matches> SignDetector::fitHomography(
    const std::vector<cv::Point3f>& object, const std::vector<cv::Point2f>& image) const {
  if (static_cast<int>(image.size()) < config_.min_inliers) return std::nullopt;
  std::vector<cv::Point2f> plane_points;
  plane_points.reserve(object.size());
  for (const cv::Point3f& p : object) plane_points.emplace_back(p.x, p.y);
  // Homography from the sign plane (metres) to pixels; the threshold is in image pixels.
  std::vector<unsigned char> inlier_mask;
  const cv::Mat homography = cv::findHomography(
      plane_points, image, cv::RANSAC, config_.ransac_threshold_px, inlier_mask, 2000, 0.999);
  if (homography.empty()) return std::nullopt;
  Matches matches;
  matches.plane_to_image = cv::Matx33d(homography.ptr<double>());
  for (size_t i = 0; i < inlier_mask.size(); ++i) {
    if (!inlier_mask[i]) continue;
    matches.object.push_back(object[i]);
    matches.image.push_back(image[i]);
  }
  if (static_cast<int>(matches.image.size()) < config_.min_inliers) return std::nullopt;

  // The sign must appear unmirrored: a homography that flips it is a false match.
  std::vector<cv::Point2d> outline;
  cv::perspectiveTransform(outlinePlane(), outline, matches.plane_to_image);
  const std::vector<cv::Point2f> outline_f(outline.begin(), outline.end());
  if (!cv::isContourConvex(outline_f) || signedArea(outline_f) <= 0.0) return std::nullopt;
  return matches;
}

std::optional<SignDetector::Matches> SignDetector::trackInto(const cv::Mat& gray) const {
  std::vector<cv::Point2d> before;
  cv::perspectiveTransform(outlinePlane(), before, last_plane_to_image_);
  const std::vector<cv::Point2f> outline(before.begin(), before.end());
  const cv::Rect whole(0, 0, gray.cols, gray.rows);
  const cv::Rect sign = cv::boundingRect(outline) & whole;
  if (sign.empty()) return std::nullopt;
  // Corners in the last frame well inside the sign: along its outline the camera sees it
  // blended with a background that moves differently.
  // A big sign's corners are found on a block-averaged copy: enough of them, for less.
  const int f = std::max(1, static_cast<int>(std::ceil(std::max(sign.width, sign.height) /
                                                       static_cast<double>(kCornersMaxPx))));
  const cv::Size size(sign.width / f, sign.height / f);
  if (size.width < 1 || size.height < 1) return std::nullopt;
  cv::Mat searched = last_frame_(cv::Rect(sign.tl(), size * f));
  if (f > 1) cv::resize(searched, searched, size, 0, 0, cv::INTER_AREA);
  std::vector<cv::Point> polygon;
  polygon.reserve(outline.size());
  for (const cv::Point2f& p : outline) {
    polygon.emplace_back(cvRound((p.x - sign.x) * 16 / f), cvRound((p.y - sign.y) * 16 / f));
  }
  cv::Mat mask = cv::Mat::zeros(size, CV_8UC1);
  cv::fillConvexPoly(mask, polygon, cv::Scalar(255), cv::LINE_8, 4);
  const int edge_band = (kEdgeBandPx + f - 1) / f;
  const cv::Size band(2 * edge_band + 1, 2 * edge_band + 1);
  cv::erode(mask, mask, cv::getStructuringElement(cv::MORPH_ELLIPSE, band));
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(searched, corners, config_.track_features, kTrackCornerQuality,
                          kTrackCornerSpacingPx, mask);
  // Reduced pixel q covers full pixels f q ... f q + f - 1.
  for (cv::Point2f& p : corners) p = p * static_cast<float>(f) + cv::Point2f(0.5f, 0.5f) * (f - 1);
  if (static_cast<int>(corners.size()) < config_.min_inliers) return std::nullopt;

  // Followed within the reach of the fastest allowed motion (plus the window) around the sign.
  const int reach =
      static_cast<int>(std::ceil(config_.max_track_motion_px)) + config_.track_window_px;
  const cv::Rect region =
      cv::Rect(sign.x - reach, sign.y - reach, sign.width + 2 * reach, sign.height + 2 * reach) &
      whole;
  const cv::Point2f shift(static_cast<float>(sign.x - region.x),
                          static_cast<float>(sign.y - region.y));
  for (cv::Point2f& p : corners) p += shift;
  std::vector<cv::Point2f> followed;
  std::vector<unsigned char> status;
  std::vector<float> errors;
  cv::calcOpticalFlowPyrLK(last_frame_(region), gray(region), corners, followed, status, errors,
                           cv::Size(config_.track_window_px, config_.track_window_px),
                           config_.track_levels,
                           cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS,
                                            kTrackIterations, kTrackEpsilonPx));
  const cv::Point2f offset(static_cast<float>(region.x), static_cast<float>(region.y));
  std::vector<cv::Point2f> from, to;
  for (size_t i = 0; i < corners.size(); ++i) {
    if (!status[i] || !(cv::norm(followed[i] - corners[i]) <= config_.max_track_motion_px)) {
      continue;
    }
    from.push_back(corners[i] + offset);
    to.push_back(followed[i] + offset);
  }
  if (static_cast<int>(from.size()) < config_.min_inliers) return std::nullopt;
  // Where the corners lie on the sign, by the last frame's aligned homography.
  std::vector<cv::Point2f> on_plane;
  cv::perspectiveTransform(from, on_plane, cv::Mat(last_plane_to_image_.inv()));
  std::vector<cv::Point3f> object;
  object.reserve(on_plane.size());
  for (const cv::Point2f& p : on_plane) object.emplace_back(p.x, p.y, 0.0f);
  std::optional<Matches> matches = fitHomography(object, to);
  if (!matches) return std::nullopt;
  std::vector<cv::Point2d> after;
  cv::perspectiveTransform(outlinePlane(), after, matches->plane_to_image);
  for (size_t i = 0; i < after.size(); ++i) {
    if (!(cv::norm(after[i] - before[i]) <= config_.max_track_motion_px)) return std::nullopt;
  }
  return matches;
}

std::vector<cv::Point2d> SignDetector::outlinePlane() const {
  const double half_w = config_.width_m / 2.0;
  const double half_h = height_m_ / 2.0;
  return {{-half_w, -half_h}, {half_w, -half_h}, {half_w, half_h}, {-half_w, half_h}};
}

void SignDetector::reset() {
  previous_rotation_.reset();
  search_window_.reset();
  last_frame_.release();
  last_tracked_ = false;
}

std::optional<MarkerObservation> SignDetector::detect(const cv::Mat& gray,
                                                      const CameraGeometry& camera) {
  last_tracked_ = false;
  if (gray.empty() || gray.type() != CV_8UC1) return std::nullopt;
  if (gray.size() != frame_size_) {  // another camera or resolution: nothing carries over
    reset();
    frame_size_ = gray.size();
  }
  std::optional<MarkerObservation> seen;
  if (!last_frame_.empty()) {
    if (const std::optional<Matches> tracked = trackInto(gray)) {
      seen = poseFrom(gray, camera, *tracked, /*tracked=*/true);
      last_tracked_ = seen.has_value();
    }
  }
  if (!seen) {
    const cv::Rect whole(0, 0, gray.cols, gray.rows);
    // Search near the last sighting first: SIFT over the whole frame is most of the cost.
    std::optional<Matches> matches;
    if (search_window_) matches = matchIn(gray, *search_window_ & whole, search_half_resolution_);
    if (!matches && search_window_ != whole) matches = matchIn(gray, whole, false);
    search_window_.reset();
    if (matches) seen = poseFrom(gray, camera, *matches, /*tracked=*/false);
  }
  if (seen && config_.track) {
    gray.copyTo(last_frame_);
  } else {
    last_frame_.release();
  }
  return seen;
}

std::optional<MarkerObservation> SignDetector::poseFrom(const cv::Mat& gray,
                                                        const CameraGeometry& camera,
                                                        const Matches& matches, bool tracked) {
  const std::vector<cv::Point3f>& inlier_object = matches.object;
  // The pose is the rectified camera's: points of a raw frame go through the lens first.
  const std::vector<cv::Point2f> inlier_image = rectifyPixels(camera, matches.image);

  // Pose points: a grid over the sign mapped by the aligned homography, or else the inlier
  // keypoints themselves. A second pass renders from the first pass's better homography. The
  // homography is the rectified camera's: through a lens, the one through the rectified inliers.
  cv::Matx33d plane_to_image = matches.plane_to_image;
  if (camera.lens) {
    std::vector<cv::Point2f> inlier_plane;
    inlier_plane.reserve(inlier_object.size());
    for (const cv::Point3f& p : inlier_object) inlier_plane.emplace_back(p.x, p.y);
    const cv::Mat through_inliers = cv::findHomography(inlier_plane, inlier_image);
    if (through_inliers.empty()) return std::nullopt;
    plane_to_image = cv::Matx33d(through_inliers.ptr<double>());
  }
  std::vector<cv::Point3f> pose_object = inlier_object;
  std::vector<cv::Point2f> pose_image = inlier_image;
  // Only the alignment to the reference vouches for a tracked homography.
  const int wanted = tracked ? config_.track_refine_passes : config_.refine_passes;
  const int iterations = tracked ? config_.track_refine_iterations : config_.refine_iterations;
  int passes = 0;
  while (passes < wanted && refineHomography(gray, camera, iterations, plane_to_image)) {
    ++passes;
  }
  if (tracked && passes < wanted) return std::nullopt;
  if (passes > 0) {
    pose_object.clear();
    std::vector<cv::Point2f> grid;
    for (double fy : {-0.5, -0.25, 0.0, 0.25, 0.5}) {
      for (double fx : {-0.5, -0.25, 0.0, 0.25, 0.5}) {
        pose_object.emplace_back(fx * config_.width_m, fy * height_m_, 0.0f);
        grid.emplace_back(pose_object.back().x, pose_object.back().y);
      }
    }
    cv::perspectiveTransform(grid, pose_image, cv::Mat(plane_to_image));
  }

  // Planar pose: IPPE gives both solutions of the plane's two-fold ambiguity, best first.
  const cv::Matx33d k(camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0);
  std::vector<cv::Mat> rvecs, tvecs;
  cv::Mat errors;
  const int solutions =
      cv::solvePnPGeneric(pose_object, pose_image, k, cv::noArray(), rvecs, tvecs, false,
                          cv::SOLVEPNP_IPPE, cv::noArray(), cv::noArray(), errors);
  if (solutions < 1) return std::nullopt;
  std::vector<cv::Matx33d> rotations(solutions);
  for (int i = 0; i < solutions; ++i) cv::Rodrigues(rvecs[i], rotations[i]);
  int chosen = 0;
  if (solutions == 2 && previous_rotation_ &&
      errors.at<double>(1) - errors.at<double>(0) < config_.ambiguity_px &&
      rotationAngle(*previous_rotation_, rotations[1]) <
          rotationAngle(*previous_rotation_, rotations[0])) {
    chosen = 1;
  }
  cv::Mat rvec = rvecs[chosen].clone();
  cv::Mat tvec = tvecs[chosen].clone();
  cv::solvePnPRefineLM(pose_object, pose_image, k, cv::noArray(), rvec, tvec);

  MarkerObservation observation;
  observation.id = 0;
  cv::Rodrigues(rvec, observation.rotation);
  observation.translation = cv::Vec3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  if (!(observation.translation[2] > 0.0)) return std::nullopt;

  std::vector<cv::Point2f> reprojected;
  cv::projectPoints(inlier_object, rvec, tvec, k, cv::noArray(), reprojected);
  double squared = 0.0;
  for (size_t i = 0; i < reprojected.size(); ++i) {
    const cv::Point2f d = reprojected[i] - inlier_image[i];
    squared += d.dot(d);
  }
  observation.reprojection_error_px = std::sqrt(squared / reprojected.size());
  if (!(observation.reprojection_error_px <= config_.max_reprojection_error_px)) {
    return std::nullopt;
  }
  std::vector<cv::Point3f> outline3d;
  for (const cv::Point2d& c : outlinePlane()) outline3d.emplace_back(c.x, c.y, 0.0f);
  std::vector<cv::Point2f> corners;
  cv::projectPoints(outline3d, rvec, tvec, k, cv::noArray(), corners);
  for (size_t i = 0; i < 4; ++i) observation.corners[i] = corners[i];
  observation.quality = static_cast<double>(inlier_image.size());
  previous_rotation_ = observation.rotation;
  last_plane_to_image_ = plane_to_image;
  if (camera.lens) {  // tracking works on raw frames: the homography closest to the lens there
    std::vector<cv::Point2d> grid, rectified;
    for (double fy = -0.5; fy <= 0.5; fy += 0.125) {
      for (double fx = -0.5; fx <= 0.5; fx += 0.125) {
        grid.emplace_back(fx * config_.width_m, fy * height_m_);
      }
    }
    cv::perspectiveTransform(grid, rectified, plane_to_image);
    const cv::Mat raw = cv::findHomography(grid, unrectifyPixels(camera, rectified));
    if (raw.empty()) return std::nullopt;
    last_plane_to_image_ = cv::Matx33d(raw.ptr<double>());
  }
  // Next search window: the sign's box grown by half its size and kSearchMarginPx each way,
  // enough for a turn at the robot's top rate between two frames. A big sign has plenty of
  // keypoints at half resolution (the alignment restores the accuracy) for a quarter of the cost.
  const cv::Rect box = cv::boundingRect(corners);
  search_half_resolution_ = std::min(box.width, box.height) > kHalfResolutionSignPx;
  const int grow_x = box.width / 2 + kSearchMarginPx;
  const int grow_y = box.height / 2 + kSearchMarginPx;
  search_window_ =
      cv::Rect(box.x - grow_x, box.y - grow_y, box.width + 2 * grow_x, box.height + 2 * grow_y);
  return observation;
}

}  // namespace follow_bot
