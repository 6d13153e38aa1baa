// Runs a marker detector (the parking sign or an AprilTag) over image files and prints one JSON
// line per frame: whether the marker was found, its pose in the camera optical frame, its corners
// and the detection time (wall and process CPU, ms). Used by tests/test_sign_pose.py and
// tests/test_tag_pose_accuracy.py to check poses on frames rendered by the harness.
//
//   marker_probe (--sign IMAGE --width W | --tag-size S [--tag-id N] [--tag-family F])
//                [--fx F --fy F --cx C --cy C] [--independent] FRAME...
//
// Intrinsics default to the harness camera (640x480, 60 deg HFOV). Frames are read as grey
// levels. One detector sees the frames in order, as a node would (its previous pose settles the
// planar ambiguity); --independent makes a fresh detector for every frame instead.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "follow_bot/sign_detector.h"
#include "follow_bot/tag_detector.h"

namespace {

struct Options {
  std::string sign_image;
  double sign_width_m = 0.0;
  std::optional<follow_bot::TagDetectorConfig> tag;  // set by --tag-size: detect an AprilTag
  follow_bot::CameraGeometry camera;
  bool independent = false;
  std::vector<std::string> frames;
};

[[noreturn]] void usage(const std::string& problem) {
  std::cerr << "marker_probe: " << problem << "\n"
            << "usage: marker_probe (--sign IMAGE --width W | --tag-size S [--tag-id N]"
               " [--tag-family F])\n"
               "                    [--fx F --fy F --cx C --cy C] [--independent] FRAME...\n";
  std::exit(2);
}

double number(const std::string& flag, const char* text) {
  char* end = nullptr;
  const double value = std::strtod(text, &end);
  if (end == text || *end != '\0') usage(flag + " needs a number, got '" + text + "'");
  return value;
}

// The tag options given so far; the first one switches the probe to AprilTag mode.
follow_bot::TagDetectorConfig& tagConfig(Options& options) {
  if (!options.tag) options.tag.emplace();
  return *options.tag;
}

Options parse(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--independent") {
      options.independent = true;
    } else if (arg.rfind("--", 0) == 0 && !has_value) {
      usage(arg + " needs a value");
    } else if (arg == "--sign") {
      options.sign_image = argv[++i];
    } else if (arg == "--width") {
      options.sign_width_m = number(arg, argv[++i]);
    } else if (arg == "--tag-size") {
      tagConfig(options).size_m = number(arg, argv[++i]);
    } else if (arg == "--tag-id") {
      tagConfig(options).id = static_cast<int>(number(arg, argv[++i]));
    } else if (arg == "--tag-family") {
      tagConfig(options).family = argv[++i];
    } else if (arg == "--fx") {
      options.camera.fx = number(arg, argv[++i]);
    } else if (arg == "--fy") {
      options.camera.fy = number(arg, argv[++i]);
    } else if (arg == "--cx") {
      options.camera.cx = number(arg, argv[++i]);
    } else if (arg == "--cy") {
      options.camera.cy = number(arg, argv[++i]);
    } else if (arg.rfind("--", 0) == 0) {
      usage("unknown option " + arg);
    } else {
      options.frames.push_back(arg);
    }
  }
  if (options.sign_image.empty() == !options.tag) {
    usage("give either --sign IMAGE --width W or --tag-size S");
  }
  if (options.frames.empty()) usage("no frames given");
  return options;
}

// The one place that knows which detector the options ask for.
std::unique_ptr<follow_bot::MarkerDetector> makeDetector(const Options& options) {
  if (options.tag) return std::make_unique<follow_bot::TagDetector>(*options.tag);
  follow_bot::SignDetectorConfig config;
  config.image_path = options.sign_image;
  config.width_m = options.sign_width_m;
  return std::make_unique<follow_bot::SignDetector>(config);
}

// CPU time of the whole process (all of OpenCV's worker threads), milliseconds.
double processCpuMs() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return now.tv_sec * 1e3 + now.tv_nsec * 1e-6;
}

void printObservation(const std::string& frame, const follow_bot::MarkerObservation* seen,
                      double detect_ms, double detect_cpu_ms) {
  std::printf("{\"frame\": \"%s\", \"detect_ms\": %.3f, \"detect_cpu_ms\": %.3f, \"found\": %s",
              frame.c_str(), detect_ms, detect_cpu_ms, seen ? "true" : "false");
  if (seen) {
    const cv::Vec3d& t = seen->translation;
    const cv::Matx33d& r = seen->rotation;
    std::printf(", \"translation\": [%.6f, %.6f, %.6f]", t[0], t[1], t[2]);
    std::printf(", \"rotation\": [[%.8f, %.8f, %.8f], [%.8f, %.8f, %.8f], [%.8f, %.8f, %.8f]]",
                r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2));
    std::printf(", \"corners\": [");
    for (size_t i = 0; i < seen->corners.size(); ++i) {
      std::printf("%s[%.3f, %.3f]", i ? ", " : "", seen->corners[i].x, seen->corners[i].y);
    }
    std::printf("], \"quality\": %.1f, \"reprojection_error_px\": %.4f", seen->quality,
                seen->reprojection_error_px);
  }
  std::printf("}\n");
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = parse(argc, argv);
  std::unique_ptr<follow_bot::MarkerDetector> detector;
  try {
    detector = makeDetector(options);
  } catch (const std::invalid_argument& error) {
    std::cerr << "marker_probe: " << error.what() << "\n";
    return 1;
  }
  for (const std::string& path : options.frames) {
    const cv::Mat gray = cv::imread(path, cv::IMREAD_GRAYSCALE);
    if (gray.empty()) {
      std::cerr << "marker_probe: cannot read frame '" << path << "'\n";
      return 1;
    }
    if (options.independent) detector = makeDetector(options);
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = processCpuMs();
    const auto seen = detector->detect(gray, options.camera);
    const double cpu_ms = processCpuMs() - cpu_start;
    const std::chrono::duration<double, std::milli> elapsed =
        std::chrono::steady_clock::now() - start;
    printObservation(path, seen ? &*seen : nullptr, elapsed.count(), cpu_ms);
  }
  return 0;
}
