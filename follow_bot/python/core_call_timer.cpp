// The C++ side of the Python-binding benchmark (tools/python_core_bench.py): times
// LineDetector::detect (BGR frames), TagDetector::detect (grey frames, default config and
// camera), SignDetector::detect (grey frames, the sign IMAGE W m wide, default camera) or the pd
// steering law's step on the LineDetector's measurement of each BGR frame (stamps 1/30 s apart)
// over image files, the same way the benchmark times the Python calls, and prints the mean
// process CPU microseconds per call of the fastest round as one JSON line.
//
//   core_call_timer (--line | --tag | --sign IMAGE W | --steer) [--rounds R] [--calls N] FRAME...
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "follow_bot/line_detector.h"
#include "follow_bot/sign_detector.h"
#include "follow_bot/steering_law.h"
#include "follow_bot/tag_detector.h"

namespace {

constexpr const char* kUsage =
    "usage: core_call_timer (--line | --tag | --sign IMAGE W | --steer) [--rounds R] [--calls N] "
    "FRAME...\n\n"
    "Times N detect() calls per frame over all frames, R rounds after one warm-up call per\n"
    "frame (defaults 5 and 20), and prints {\"us_per_call\": fastest round's mean} as JSON.\n";

// Process CPU time, in microseconds: time the scheduler gave other processes does not count,
// so the figures hold on a busy machine.
double cpuMicroseconds() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return now.tv_sec * 1e6 + now.tv_nsec * 1e-3;
}

int usageError(const std::string& problem) {
  std::cerr << "core_call_timer: " << problem << "\n" << kUsage;
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && (!std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h"))) {
    std::cout << kUsage;
    return 0;
  }
  const std::string mode = argc >= 2 ? argv[1] : "";
  if (mode != "--line" && mode != "--tag" && mode != "--sign" && mode != "--steer") {
    return usageError("give --line, --tag, --sign IMAGE W or --steer first");
  }
  follow_bot::SignDetectorConfig sign;
  int first = 2;
  if (mode == "--sign") {
    if (argc < 4) return usageError("--sign needs the sign's IMAGE and width W (m)");
    sign.image_path = argv[2];
    sign.width_m = std::atof(argv[3]);
    first = 4;
  }
  const bool colour = mode == "--line" || mode == "--steer";
  int rounds = 5;
  int calls = 20;
  std::vector<cv::Mat> frames;
  for (int i = first; i < argc; ++i) {
    int* count = !std::strcmp(argv[i], "--rounds")  ? &rounds
                 : !std::strcmp(argv[i], "--calls") ? &calls
                                                    : nullptr;
    if (count != nullptr) {
      if (i + 1 >= argc || (*count = std::atoi(argv[i + 1])) < 1) {
        return usageError(std::string(argv[i]) + " needs a count >= 1");
      }
      ++i;
      continue;
    }
    frames.push_back(cv::imread(argv[i], colour ? cv::IMREAD_COLOR : cv::IMREAD_GRAYSCALE));
    if (frames.back().empty()) {
      std::cerr << "core_call_timer: cannot read frame '" << argv[i] << "'\n";
      return 1;
    }
  }
  if (frames.empty()) return usageError("no frames given");

  const follow_bot::LineDetector line_detector;
  follow_bot::TagDetector tag_detector{follow_bot::TagDetectorConfig()};
  std::unique_ptr<follow_bot::SignDetector> sign_detector;
  if (mode == "--sign") sign_detector = std::make_unique<follow_bot::SignDetector>(sign);
  const follow_bot_common::CameraGeometry camera;
  const auto law = follow_bot::makeSteeringLaw(follow_bot::SteeringConfig(), std::nullopt);
  std::map<const uchar*, follow_bot::LineMeasurement> measurements;  // --steer: per frame
  for (const cv::Mat& frame : frames) measurements[frame.data] = line_detector.detect(frame);
  double stamp = 0.0;
  double seen = 0;  // results are used, so no call can be optimised away
  const auto detect = [&](const cv::Mat& frame) {
    if (mode == "--line") {
      seen += line_detector.detect(frame).band.pixel_count;
    } else if (mode == "--tag") {
      seen += tag_detector.detect(frame, camera).has_value();
    } else if (mode == "--sign") {
      seen += sign_detector->detect(frame, camera).has_value();
    } else {
      stamp += 1.0 / 30.0;
      seen += law->step({measurements[frame.data], stamp, {}}).angular;
    }
  };
  for (const cv::Mat& frame : frames) detect(frame);
  double fastest_us = 1e300;
  for (int round = 0; round < rounds; ++round) {
    const double start = cpuMicroseconds();
    for (const cv::Mat& frame : frames) {
      for (int call = 0; call < calls; ++call) detect(frame);
    }
    const double took = cpuMicroseconds() - start;
    fastest_us = std::min(fastest_us, took / (static_cast<double>(frames.size()) * calls));
  }
  std::printf("{\"us_per_call\": %.3f, \"frames\": %zu, \"checksum\": %g}\n", fastest_us,
              frames.size(), seen);
  return 0;
}
