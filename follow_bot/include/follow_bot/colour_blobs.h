// Finds a blob of each of a few named colours (red, green, blue beacons) in a BGR frame, as the
// lecture's Lab 5 does: HSV threshold, morphological clean-up, external contours, the chosen
// contour's moments, enclosing circle and bounding box. Any shape: the largest blob wins; balls:
// the nearest (largest circle) of the blobs that fit one.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot/BeaconChaserDefaults.h"
#include "follow_bot/common.h"
#include "follow_bot_common/config_fields.h"
#include "follow_bot_common/ground_projection.h"

namespace follow_bot {

// A colour as a hue window plus saturation and value floors, in OpenCV's 8-bit HSV (H 0..179,
// degrees / 2; S and V 0..255). Hues within `sensitivity` of `hue_centre` match (and at most
// `hue_offset_max` above it), wrapping around the hue circle, so red (centre 0) takes 0..s and
// 180 - s..179.
struct ColourSpec {
  std::string name;
  int hue_centre = 0;                                   // 0..179
  int sensitivity = BeaconChaserDefaults::sensitivity;  // 0..90; 90 accepts every hue
  // Grey floor and white walls have S near 0 and lose their hue to noise; S >= 100 rejects
  // them. The floor V (20) keeps the shaded faces of the dark-green dumpster (V ~ 70).
  int s_min = BeaconChaserDefaults::s_min;  // 0..255
  int v_min = BeaconChaserDefaults::v_min;  // 0..255
  // A blob counts only when the median hue of its pixels lies in [hue_centre + median_hue_min,
  // hue_centre + median_hue_max] (-90..90, wrapping). An orange object's shaded side is as red as
  // a red one (smarties: orange sweets' pixels span hue 0..17, their median 6..9), so red is told
  // from orange by the whole blob, not pixel by pixel.
  int median_hue_min = -90;
  int median_hue_max = 90;
  // Pixels count up to this far above hue_centre even where sensitivity reaches further. Red's
  // is 10: a wood floor (hue 14-15, S 100-150) sits inside a window of 15, and a red ball on it
  // merged with the floor into one blob, orange by its median, so the ball was not found.
  int hue_offset_max = 90;
};

// The default spec of "red" (hue 0, pixels up to hue 10, blobs with a median hue from -8 to 3:
// orange and pink things are not red), "green" (60) or "blue" (120); nullopt for other names.
std::optional<ColourSpec> parseColourName(const std::string& name);

// Fills `specs` with the default specs of `names` (e.g. a ROS list parameter). Returns "" on
// success, else a message naming the first unknown name; `specs` is then left unchanged.
std::string colourSpecsFromNames(const std::vector<std::string>& names,
                                 std::vector<ColourSpec>& specs);

struct ColourBlobConfig {
  std::vector<ColourSpec> colours{*parseColourName("red"), *parseColourName("green"),
                                  *parseColourName("blue")};
  // Morphological opening (removes specks smaller than the kernel) then closing (fills
  // pinholes and cracks), with elliptical kernels of these odd sizes; 0 or 1 turns a step off.
  // Odd sizes keep the kernel centred, so neither step shifts a blob.
  int open_kernel = 3;
  int close_kernel = 5;
  // A colour is found when one of its external contours encloses at least this many px^2.
  double min_area = BeaconChaserDefaults::min_area;
  // For balls: a contour counts when its boundary's RMS distance to the circle that best fits it
  // is at most the band, 1 px (pixel quantisation) plus this fraction of that circle's radius.
  // Otherwise (a real ball's mask takes in its shadow, loses a notch to a seam or a highlight, or
  // another object hides part of it, balls touch) for each circle RANSAC finds that has
  // boundary pixels within the band along most of its arc (two thirds or more of it inside the
  // frame) and is 40 % or more filled by the blob; the blob is then cut to that circle. Boundary
  // pixels on the image border are left out, so a ball cut by the frame's edge is judged by its
  // arc; posters, boxes, tape, shadows and crescents are not round. 0: any shape, as the lab
  // worksheet's colour steps and an approached box take it.
  double roundness_tolerance = BeaconChaserDefaults::roundness_tolerance;
  // For balls of a known size resting on the floor: a contour counts only when the ball its
  // circle implies (floorBallRadius) has this radius within `tolerance` (a fraction of it).
  // A wall picture lies above the horizon, a smaller or larger ball has another radius. Empty:
  // any size, as the lab worksheet's colour steps take it; the beacon chaser sets its
  // ~ball_radius and ~ball_size_tolerance.
  struct FloorBall {
    double radius_m = 0.0;
    double tolerance = 0.0;
    CameraGeometry camera;
  };
  std::optional<FloorBall> floor_ball;

  static constexpr auto fields() {
    using C = ColourBlobConfig;
    return std::make_tuple(
        field("open_kernel", &C::open_kernel), field("close_kernel", &C::close_kernel),
        cfgField("min_area", &C::min_area, atLeast(0.0)),
        field("roundness_tolerance", &C::roundness_tolerance, inRange(0.0, 1.0)));
  }
};

// Empty when the configuration is usable, otherwise a message naming the first bad field,
// e.g. "colours[1] (green): sensitivity must be in [0, 90], got 95".
std::string validate(const ColourBlobConfig& config);

// How far `contour` strays from the circle that best fits it (least squares, Kasa): the RMS of
// its boundary pixels' distances to that circle, and the circle's radius, in px. Pixels on the
// border of an `image`-sized frame are left out. Nullopt when fewer than 5 pixels remain or
// they fit no circle (a straight run): the shape cannot be judged.
struct CircleFit {
  cv::Point2d centre;
  double radius = 0.0;
  double rms_error = 0.0;
};
std::optional<CircleFit> fitCircle(const std::vector<cv::Point>& contour, cv::Size image);

// The radius of the ball resting on the floor whose silhouette has the circle (`centre`,
// `radius_px`, raw image pixels) in `camera`'s view: the circle's ends on the line through the
// principal point are the rays tangent to the ball (see sphereCentreFromCircle), so their
// bisector points at its centre, at angle theta below the horizontal, and half the angle
// between them is its angular radius alpha; a ball of radius r touching the floor has its
// centre r below the camera's height h, hence r = h / (1 + sin(theta) / sin(alpha)). Nullopt
// when no ball on the floor fits (the circle is too high in the view: a wall picture) or the
// input is unusable.
std::optional<double> floorBallRadius(const CameraGeometry& camera, const cv::Point2d& centre,
                                      double radius_px);

// The chosen blob of one colour. All geometry is in full-image pixel coordinates with pixel
// centres at integer positions (as cv::moments); every field but `name` is zero/empty unless
// `found`.
struct ColourBlob {
  std::string name;
  bool found = false;
  int blob_count = 0;         // contours of this colour with area >= min_area that pass the gates
  double area = 0.0;          // px^2 enclosed by `contour` (cv::contourArea)
  cv::Point2d centroid;       // of the area enclosed by the contour (contour moments)
  cv::Point2f circle_centre;  // minimum enclosing circle of the contour
  float circle_radius = 0.0f;
  cv::Rect bounding_box;           // inclusive pixels, as cv::boundingRect
  std::vector<cv::Point> contour;  // every boundary pixel (CHAIN_APPROX_NONE)
  // Every counted blob's circle (x, y, radius; a ball's fitted circle, else the enclosing one),
  // the chosen blob's first.
  std::vector<cv::Vec3f> circles;
};

struct BlobResult {
  std::string error;  // why the frame was rejected; empty when it was processed
  int image_width = 0;
  int image_height = 0;
  std::vector<ColourBlob> colours;  // one per configured colour, in configuration order
  bool ok() const { return error.empty(); }
  // The blob of the named colour, or nullptr when that colour is not configured.
  const ColourBlob* find(const std::string& name) const;
};

class ColourBlobDetector {
 public:
  // Throws std::invalid_argument with the validate() message when the configuration is unusable.
  explicit ColourBlobDetector(const ColourBlobConfig& config = ColourBlobConfig());

  // Measures every configured colour in a CV_8UC3 BGR frame. One BGR->HSV conversion is shared
  // by all colours. The frame is processed at full resolution: the whole pipeline costs a few
  // ms on 640x480 and downscaling would cost the pixel accuracy the range estimates need.
  // Never throws: an empty or non-CV_8UC3 frame gives a result with `error` set and every
  // colour not found.
  BlobResult detect(const cv::Mat& bgr) const;

  // The cleaned-up binary mask (CV_8UC1, 255 = colour) that detect() finds the named colour's
  // blobs in; empty for frames detect() rejects or an unconfigured name.
  cv::Mat mask(const cv::Mat& bgr, const std::string& name) const;

  const ColourBlobConfig& config() const { return config_; }

  // Draws each found blob of `blobs` on `bgr`: its contour, enclosing circle and name.
  static void drawDebug(cv::Mat& bgr, const BlobResult& blobs);

 private:
  struct Candidate;
  void cleanedMask(const cv::Mat& hsv, const ColourSpec& spec, cv::Mat& mask) const;
  // Adds to `candidates` the blob of `contour` as the gates (roundness, floor ball, median hue)
  // take it, or when it is not round as a whole, each ball RANSAC finds in it, cut to its circle.
  void judge(const std::vector<cv::Point>& contour, const cv::Mat& hsv, const ColourSpec& spec,
             std::vector<Candidate>& candidates) const;
  // A blob judge() took nothing from may be a ball on a floor of nearly its colour (a red ball on
  // reddish wood), one blob in the mask: judges its part more saturated than the saturation
  // Otsu's method fits to its pixels, when the two parts differ clearly.
  void judgeSaturatedPart(const std::vector<cv::Point>& contour, const cv::Mat& mask,
                          const cv::Mat& hsv, const ColourSpec& spec,
                          std::vector<Candidate>& candidates) const;
  // The floor-ball and median-hue gates on one blob's outline (`ball`: its circle, if judged).
  bool acceptable(const std::optional<CircleFit>& ball, const std::vector<cv::Point>& contour,
                  const cv::Mat& hsv, const ColourSpec& spec) const;

  ColourBlobConfig config_;
  cv::Mat open_kernel_;   // empty when opening is off
  cv::Mat close_kernel_;  // empty when closing is off
};

}  // namespace follow_bot
