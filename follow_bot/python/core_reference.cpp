// The C++ side of tests/bindings/test_python_core.py: runs a default-configured LineDetector,
// ColourBlobDetector, steering law (on the LineDetector's measurements) or parking servo (on a
// TagDetector's observations) over image files in order and prints one JSON line per frame with
// every result field, doubles at 17 significant digits (exact), so the test can compare
// follow_bot.core's results with the C++ library's.
//
//   core_reference (--line | --blobs) FRAME...
//   core_reference --steer (lecture | pd | path) FRAME...
//   core_reference --park TAG_SIZE TAG_ID TAG_FAMILY FRAME...
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <optional>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "follow_bot/colour_blobs.h"
#include "follow_bot/line_detector.h"
#include "follow_bot/parking_servo.h"
#include "follow_bot/steering_law.h"
#include "follow_bot/tag_detector.h"

namespace {

constexpr const char* kUsage =
    "usage: core_reference (--line | --blobs | --blobs-any-shape) FRAME...\n"
    "       core_reference --steer (lecture | pd | path) FRAME...\n"
    "       core_reference --park TAG_SIZE TAG_ID TAG_FAMILY FRAME...\n\n"
    "Runs the default LineDetector (--line), ColourBlobDetector (--blobs; --blobs-any-shape:\n"
    "without the roundness gate, as for a box target), the steering law of\n"
    "that mode on the LineDetector's measurements (--steer; frames 1/30 s apart, each applying\n"
    "the previous command) or the ParkingServo on a TagDetector's poses (--park; default camera,\n"
    "frames 1/30 s apart) on each image file in order and prints one JSON line per frame with\n"
    "every result field (doubles exact).\n";

// Frames are this far apart (s) in --steer and --park.
constexpr double kFramePeriod = 1.0 / 30.0;

void printBand(const char* name, const follow_bot::BandMeasurement& band) {
  std::printf(
      ", \"%s\": {\"found\": %s, \"pixel_count\": %d, \"centroid_x\": %.17g, \"centroid_y\": "
      "%.17g, "
      "\"error_px\": %.17g, \"error_normalised\": %.17g, \"confidence\": %.17g, \"row_begin\": %d, "
      "\"row_end\": %d, \"centre_pixel_count\": %d, \"centre_found\": %s, \"centre_x\": %.17g, "
      "\"centre_y\": %.17g}",
      name, band.found ? "true" : "false", band.pixel_count, band.centroid_x, band.centroid_y,
      band.error_px, band.error_normalised, band.confidence, band.row_begin, band.row_end,
      band.centre_pixel_count, band.centre_found ? "true" : "false", band.centre_x, band.centre_y);
}

void printLine(const follow_bot::LineMeasurement& m) {
  std::printf(R"("image_width": %d, "image_height": %d)", m.image_width, m.image_height);
  printBand("band", m.band);
  printBand("look_ahead", m.look_ahead);
}

void printBlobs(const follow_bot::BlobResult& result) {
  std::printf(R"("image_width": %d, "image_height": %d, "colours": [)", result.image_width,
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

void printTwist(const follow_bot::Twist2D& twist) {
  std::printf(R"("linear": %.17g, "angular": %.17g)", twist.linear, twist.angular);
}

// --steer MODE FRAME...: one law over the frames, as the follower drives it.
int steer(int argc, char** argv) {
  follow_bot::SteeringConfig config;
  const auto mode = follow_bot::parseSteeringMode(argv[2]);
  if (!mode) {
    std::cerr << "core_reference: unknown steering mode '" << argv[2] << "'\n" << kUsage;
    return 2;
  }
  config.mode = *mode;
  const auto law = follow_bot::makeSteeringLaw(config, follow_bot_common::CameraGeometry());
  const follow_bot::LineDetector detector;
  follow_bot::Twist2D applied;
  for (int i = 3; i < argc; ++i) {
    const cv::Mat frame = cv::imread(argv[i], cv::IMREAD_COLOR);
    if (frame.empty()) {
      std::cerr << "core_reference: cannot read frame '" << argv[i] << "'\n";
      return 1;
    }
    // A base without delay: what was sent after the last frame is what it did.
    applied =
        law->step({detector.detect(frame), (i - 3) * kFramePeriod, applied, applied, std::nullopt});
    std::printf(R"({"frame": "%s", )", argv[i]);
    printTwist(applied);
    std::printf(", \"state\": \"%s\"}\n", follow_bot::toString(law->state()));
  }
  return 0;
}

// --park SIZE ID FAMILY FRAME...: the parker's servo on the tag's poses.
int park(int argc, char** argv) {
  follow_bot::TagDetectorConfig tag;
  tag.size_m = std::stod(argv[2]);
  tag.id = std::stoi(argv[3]);
  tag.family = argv[4];
  follow_bot::TagDetector detector(tag);
  const follow_bot_common::CameraGeometry camera;
  follow_bot::ParkingServo servo{follow_bot::ParkingServoConfig()};
  for (int i = 5; i < argc; ++i) {
    const cv::Mat frame = cv::imread(argv[i], cv::IMREAD_GRAYSCALE);
    if (frame.empty()) {
      std::cerr << "core_reference: cannot read frame '" << argv[i] << "'\n";
      return 1;
    }
    const follow_bot::Twist2D twist =
        servo.update(detector.detect(frame, camera), (i - 5) * kFramePeriod);
    std::printf(R"({"frame": "%s", )", argv[i]);
    printTwist(twist);
    std::printf(R"(, "state": "%s", "error": )", follow_bot::toString(servo.state()));
    if (const auto& e = servo.lastError()) {
      std::printf(
          "{\"along\": %.17g, \"lateral\": %.17g, \"heading\": %.17g, \"phi\": %.17g, "
          "\"bearing\": %.17g}}\n",
          e->along, e->lateral, e->heading, e->phi, e->bearing);
    } else {
      std::printf("null}\n");
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && (!std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h"))) {
    std::cout << kUsage;
    return 0;
  }
  if (argc >= 4 && !std::strcmp(argv[1], "--steer")) return steer(argc, argv);
  if (argc >= 6 && !std::strcmp(argv[1], "--park")) return park(argc, argv);
  const bool line = argc >= 2 && !std::strcmp(argv[1], "--line");
  const bool any_shape = argc >= 2 && !std::strcmp(argv[1], "--blobs-any-shape");
  const bool blobs = any_shape || (argc >= 2 && !std::strcmp(argv[1], "--blobs"));
  if (argc < 3 || (!line && !blobs)) {
    std::cerr << "core_reference: give --line, --blobs, --steer MODE or --park SIZE ID FAMILY, "
                 "then at least one frame\n"
              << kUsage;
    return 2;
  }
  const follow_bot::LineDetector line_detector;
  follow_bot::ColourBlobConfig blob_config;
  if (any_shape) blob_config.roundness_tolerance = 0.0;
  const follow_bot::ColourBlobDetector blob_detector(blob_config);
  for (int i = 2; i < argc; ++i) {
    const cv::Mat frame = cv::imread(argv[i], cv::IMREAD_COLOR);
    if (frame.empty()) {
      std::cerr << "core_reference: cannot read frame '" << argv[i] << "'\n";
      return 1;
    }
    std::printf(R"({"frame": "%s", )", argv[i]);
    if (line) {
      printLine(line_detector.detect(frame));
    } else {
      printBlobs(blob_detector.detect(frame));
    }
    std::printf("}\n");
  }
  return 0;
}
