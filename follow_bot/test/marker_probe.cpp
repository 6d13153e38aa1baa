// Runs a marker detector (the parking sign or an AprilTag) over image files and prints one JSON
// line per frame: whether the marker was found, its pose in the camera optical frame, its corners
// and the detection time (wall and process CPU, ms). Used by tests/accuracy/test_sign_pose.py and
// tests/accuracy/test_tag_pose_accuracy.py to check poses on frames rendered by the harness; its
// poses, corners and quality are exact (17 significant digits) for
// tests/bindings/test_python_core.py.
//
//   marker_probe (--sign IMAGE --width W | --tag-size S [--tag-id N] [--tag-family F])
//                [--fx F --fy F --cx C --cy C] [--distortion K1,K2,P1,P2,K3] [--independent]
//                FRAME...
//
// Intrinsics default to the harness camera (640x480, 60 deg HFOV); --distortion: the frames are
// raw through that plumb_bob lens (K from --fx..--cy, R = I, P = K), as the harness renders one.
// Frames are read as grey levels. One detector sees the frames in order, as a node would (its
// previous pose settles the planar ambiguity); --independent makes a fresh detector for every frame
// instead.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <boost/program_options.hpp>
#include <opencv2/imgcodecs.hpp>

#include "follow_bot/sign_detector.h"
#include "follow_bot/tag_detector.h"

namespace {

struct Options {
  std::string sign_image;
  double sign_width_m = 0.0;
  std::optional<follow_bot::TagDetectorConfig> tag;  // set by --tag-size: detect an AprilTag
  follow_bot_common::CameraGeometry camera;
  bool independent = false;
  std::vector<std::string> frames;
};

constexpr const char* kUsage =
    "usage: marker_probe (--sign IMAGE --width W | --tag-size S [--tag-id N] [--tag-family F])\n"
    "                    [--fx F --fy F --cx C --cy C] [--distortion K1,K2,P1,P2,K3]\n"
    "                    [--independent] FRAME...\n\n"
    "Detects the parking sign or an AprilTag in each frame; prints one JSON line per frame";

namespace po = boost::program_options;

// The options from the command line. --help prints the usage and exits 0; bad usage prints
// the problem and the usage on stderr and exits 2.
Options parse(int argc, char** argv) {
  Options options;
  follow_bot::TagDetectorConfig tag;
  std::string distortion;
  po::options_description described(kUsage);
  described.add_options()("help,h", "print this help and exit")(
      "sign", po::value(&options.sign_image)->value_name("IMAGE"), "the sign's reference image")(
      "width", po::value(&options.sign_width_m)->value_name("W"), "the sign's width, m")(
      "tag-size", po::value(&tag.size_m)->value_name("S"), "detect an AprilTag this wide, m")(
      "tag-id", po::value(&tag.id)->value_name("N")->default_value(tag.id), "the tag's id")(
      "tag-family", po::value(&tag.family)->value_name("F")->default_value(tag.family),
      "the tag's family")("fx", po::value(&options.camera.fx)->default_value(options.camera.fx),
                          "focal length, px")(
      "fy", po::value(&options.camera.fy)->default_value(options.camera.fy), "focal length, px")(
      "cx", po::value(&options.camera.cx)->default_value(options.camera.cx), "principal point, px")(
      "cy", po::value(&options.camera.cy)->default_value(options.camera.cy), "principal point, px")(
      "distortion", po::value(&distortion)->value_name("K1,K2,P1,P2,K3"),
      "raw frames through this plumb_bob lens")(
      "independent", po::bool_switch(&options.independent), "a fresh detector for every frame");
  po::options_description all;
  all.add(described).add_options()("frames", po::value(&options.frames));
  po::positional_options_description positional;
  positional.add("frames", -1);
  std::string problem;
  po::variables_map values;
  try {
    po::store(po::command_line_parser(argc, argv).options(all).positional(positional).run(),
              values);
    po::notify(values);
  } catch (const po::error& error) {
    problem = error.what();
  }
  if (problem.empty() && values.count("help")) {
    std::cout << described;
    std::exit(0);
  }
  if (problem.empty() && !distortion.empty()) {
    std::vector<double> coefficients;
    std::istringstream list(distortion);
    for (std::string item; std::getline(list, item, ',');)
      coefficients.push_back(std::atof(item.c_str()));
    const cv::Matx33d k(options.camera.fx, 0, options.camera.cx, 0, options.camera.fy,
                        options.camera.cy, 0, 0, 1);
    options.camera.lens = follow_bot_common::CameraLens{k, coefficients, cv::Matx33d::eye()};
    problem = validate(options.camera);
    if (!problem.empty()) problem = "--distortion: " + problem;
  }
  if (problem.empty()) {
    if (values.count("tag-size")) options.tag = tag;
    if (options.sign_image.empty() == !options.tag) {
      problem = "give either --sign IMAGE --width W or --tag-size S";
    } else if (options.frames.empty()) {
      problem = "no frames given";
    }
  }
  if (!problem.empty()) {
    std::cerr << "marker_probe: " << problem << "\n" << described;
    std::exit(2);
  }
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
  std::printf(R"({"frame": "%s", "detect_ms": %.3f, "detect_cpu_ms": %.3f, "found": %s)",
              frame.c_str(), detect_ms, detect_cpu_ms, seen ? "true" : "false");
  if (seen) {
    const cv::Vec3d& t = seen->translation;
    const cv::Matx33d& r = seen->rotation;
    std::printf(", \"translation\": [%.17g, %.17g, %.17g]", t[0], t[1], t[2]);
    std::printf(
        ", \"rotation\": [[%.17g, %.17g, %.17g], [%.17g, %.17g, %.17g], [%.17g, %.17g, %.17g]]",
        r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2));
    std::printf(", \"corners\": [");
    for (size_t i = 0; i < seen->corners.size(); ++i) {
      std::printf("%s[%.17g, %.17g]", i ? ", " : "", seen->corners[i].x, seen->corners[i].y);
    }
    std::printf(R"(], "quality": %.17g, "reprojection_error_px": %.17g)", seen->quality,
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
