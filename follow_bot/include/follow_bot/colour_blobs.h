// Finds the largest blob of each of a few named colours (red, green, blue beacons) in a BGR
// frame, as the lecture's Lab 5 does: HSV threshold, morphological clean-up, external contours,
// the largest contour's moments, enclosing circle and bounding box.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot/BeaconChaserDefaults.h"

namespace follow_bot {

// A colour as a hue window plus saturation and value floors, in OpenCV's 8-bit HSV (H 0..179,
// degrees / 2; S and V 0..255). Hues within `sensitivity` of `hue_centre` match, wrapping
// around the hue circle, so red (centre 0) takes 0..s and 180 - s..179.
struct ColourSpec {
  std::string name;
  int hue_centre = 0;                                   // 0..179
  int sensitivity = BeaconChaserDefaults::sensitivity;  // 0..90; 90 accepts every hue
  // Grey floor and white walls have S near 0 and lose their hue to noise; S >= 100 rejects
  // them. The floor V (20) keeps the shaded faces of the dark-green dumpster (V ~ 70).
  int s_min = BeaconChaserDefaults::s_min;  // 0..255
  int v_min = BeaconChaserDefaults::v_min;  // 0..255
};

// The default spec of "red" (hue 0), "green" (60) or "blue" (120); nullopt for other names.
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
  // A colour is found when its largest external contour encloses at least this many px^2.
  double min_area = BeaconChaserDefaults::min_area;
};

// Empty when the configuration is usable, otherwise a message naming the first bad field,
// e.g. "colours[1] (green): sensitivity must be in [0, 90], got 95".
std::string validate(const ColourBlobConfig& config);

// The largest blob of one colour. All geometry is in full-image pixel coordinates with pixel
// centres at integer positions (as cv::moments); every field but `name` is zero/empty unless
// `found`.
struct ColourBlob {
  std::string name;
  bool found = false;
  int blob_count = 0;         // external contours of this colour with area >= min_area
  double area = 0.0;          // px^2 enclosed by the largest contour (cv::contourArea)
  cv::Point2d centroid;       // of the area enclosed by the contour (contour moments)
  cv::Point2f circle_centre;  // minimum enclosing circle of the contour
  float circle_radius = 0.0f;
  cv::Rect bounding_box;           // inclusive pixels, as cv::boundingRect
  std::vector<cv::Point> contour;  // every boundary pixel (CHAIN_APPROX_NONE)
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
  void cleanedMask(const cv::Mat& hsv, const ColourSpec& spec, cv::Mat& mask) const;

  ColourBlobConfig config_;
  cv::Mat open_kernel_;   // empty when opening is off
  cv::Mat close_kernel_;  // empty when closing is off
};

}  // namespace follow_bot
