// The C++ side of tests/test_python_core.py: runs a default-configured LineDetector or
// ColourBlobDetector over image files and prints one JSON line per frame with every result
// field, doubles at 17 significant digits (exact), so the test can compare follow_bot.core's
// results with the C++ library's bit for bit.
//
//   core_reference (--line | --blobs) FRAME...
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "follow_bot/colour_blobs.h"
#include "follow_bot/line_detector.h"

namespace {

constexpr const char* kUsage =
    "usage: core_reference (--line | --blobs) FRAME...\n\n"
    "Runs the default LineDetector (--line) or ColourBlobDetector (--blobs) on each BGR image\n"
    "file and prints one JSON line per frame with every result field (doubles exact).\n";

void printBand(const char* name, const follow_bot::BandMeasurement& band) {
  std::printf(
      ", \"%s\": {\"found\": %s, \"pixel_count\": %d, \"centroid_x\": %.17g, \"centroid_y\": "
      "%.17g, "
      "\"error_px\": %.17g, \"error_normalised\": %.17g, \"confidence\": %.17g, \"row_begin\": %d, "
      "\"row_end\": %d}",
      name, band.found ? "true" : "false", band.pixel_count, band.centroid_x, band.centroid_y,
      band.error_px, band.error_normalised, band.confidence, band.row_begin, band.row_end);
}

void printLine(const follow_bot::LineMeasurement& m) {
  std::printf("\"image_width\": %d, \"image_height\": %d", m.image_width, m.image_height);
  printBand("band", m.band);
  printBand("look_ahead", m.look_ahead);
}

void printBlobs(const follow_bot::BlobResult& result) {
  std::printf("\"image_width\": %d, \"image_height\": %d, \"colours\": [", result.image_width,
              result.image_height);
  for (size_t i = 0; i < result.colours.size(); ++i) {
    const follow_bot::ColourBlob& b = result.colours[i];
    std::printf(
        "%s{\"name\": \"%s\", \"found\": %s, \"blob_count\": %d, \"area\": %.17g, "
        "\"centroid\": [%.17g, %.17g], \"circle_centre\": [%.9g, %.9g], \"circle_radius\": %.9g, "
        "\"bounding_box\": [%d, %d, %d, %d], \"contour\": [",
        i ? ", " : "", b.name.c_str(), b.found ? "true" : "false", b.blob_count, b.area,
        b.centroid.x, b.centroid.y, b.circle_centre.x, b.circle_centre.y, b.circle_radius,
        b.bounding_box.x, b.bounding_box.y, b.bounding_box.width, b.bounding_box.height);
    for (size_t k = 0; k < b.contour.size(); ++k) {
      std::printf("%s[%d, %d]", k ? ", " : "", b.contour[k].x, b.contour[k].y);
    }
    std::printf("]}");
  }
  std::printf("]");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && (!std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h"))) {
    std::cout << kUsage;
    return 0;
  }
  const bool line = argc >= 2 && !std::strcmp(argv[1], "--line");
  const bool blobs = argc >= 2 && !std::strcmp(argv[1], "--blobs");
  if (argc < 3 || (!line && !blobs)) {
    std::cerr << "core_reference: give --line or --blobs, then at least one frame\n" << kUsage;
    return 2;
  }
  const follow_bot::LineDetector line_detector;
  const follow_bot::ColourBlobDetector blob_detector;
  for (int i = 2; i < argc; ++i) {
    const cv::Mat frame = cv::imread(argv[i], cv::IMREAD_COLOR);
    if (frame.empty()) {
      std::cerr << "core_reference: cannot read frame '" << argv[i] << "'\n";
      return 1;
    }
    std::printf("{\"frame\": \"%s\", ", argv[i]);
    if (line) {
      printLine(line_detector.detect(frame));
    } else {
      printBlobs(blob_detector.detect(frame));
    }
    std::printf("}\n");
  }
  return 0;
}
