// Times the lecture's line detection against follow_bot::LineDetector on the same synthetic
// 640x480 frames (a curved yellow line on noisy grey), single-threaded.
//
// Build, e.g. (one line):
//   g++ -std=c++17 -O2 -I follow_bot/include follow_bot/bench/line_detector_bench.cpp
//       follow_bot/src/core/line_detector.cpp $(pkg-config --cflags --libs opencv4) -o bench

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "follow_bot/line_detector.h"

namespace {

constexpr int kWidth = 640;
constexpr int kHeight = 480;
constexpr int kFrames = 300;
constexpr int kRounds = 5;  // timed passes over all frames, after one warm-up pass

std::vector<cv::Mat> makeFrames() {
  cv::RNG rng(42);
  std::vector<cv::Mat> frames;
  for (int i = 0; i < kFrames; ++i) {
    cv::Mat frame(kHeight, kWidth, CV_32FC3, cv::Scalar(110, 115, 120));
    // A sinuous line whose phase and drift change from frame to frame, as when driving.
    std::vector<cv::Point> line;
    const double phase = 0.07 * i;
    const double drift = 120.0 * std::sin(0.013 * i);
    for (int y = 0; y < kHeight; y += 4) {
      const double x = kWidth / 2.0 + drift + 90.0 * std::sin(phase + y / 70.0);
      line.emplace_back(cvRound(x), y);
    }
    cv::polylines(frame, line, false, cv::Scalar(30, 205, 225), 28, cv::LINE_AA);
    cv::Mat noise(frame.size(), CV_32FC3);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 12.0);
    frame += noise;
    cv::Mat bgr;
    frame.convertTo(bgr, CV_8UC3);
    frames.push_back(bgr);
  }
  return frames;
}

// The lecture, step by step: full-frame HSV, threshold, blank every row outside the band,
// moments. Returns the centroid column, or -1 when nothing is found.
double lectureCentroid(const cv::Mat& image) {
  cv::Mat hsv, mask;
  cv::cvtColor(image, hsv, cv::COLOR_BGR2HSV);
  cv::inRange(hsv, cv::Scalar(20, 100, 100), cv::Scalar(30, 255, 255), mask);
  const int h = image.rows;
  const int search_top = 3 * h / 4;
  const int search_bot = 3 * h / 4 + 20;
  for (int y = 0; y < h; ++y) {
    if (y < search_top || y >= search_bot) mask.row(y).setTo(0);
  }
  const cv::Moments m = cv::moments(mask);
  return m.m00 > 0 ? m.m10 / m.m00 : -1.0;
}

struct Stats {
  double median_us;
  double p99_us;
};

template <typename Detect>
Stats timePerFrame(const std::vector<cv::Mat>& frames, Detect&& detect) {
  volatile double sink = 0.0;  // keeps the work from being optimised away
  for (const cv::Mat& frame : frames) sink = sink + detect(frame);
  std::vector<double> micros;
  micros.reserve(frames.size() * kRounds);
  for (int round = 0; round < kRounds; ++round) {
    for (const cv::Mat& frame : frames) {
      const auto start = std::chrono::steady_clock::now();
      sink = sink + detect(frame);
      const auto stop = std::chrono::steady_clock::now();
      micros.push_back(std::chrono::duration<double, std::micro>(stop - start).count());
    }
  }
  std::sort(micros.begin(), micros.end());
  return {micros[micros.size() / 2], micros[micros.size() * 99 / 100]};
}

}  // namespace

int main() {
  cv::setNumThreads(1);
  const std::vector<cv::Mat> frames = makeFrames();
  // The lecture's bounds and band, no floor test or width gate; every line pixel counts, as in
  // the lecture, so both must find the same centroid before their speeds mean anything.
  follow_bot::LineDetectorConfig every_pixel;
  every_pixel.lower.v = 100;
  every_pixel.upper.h = 30;
  every_pixel.blob_saturation_fraction = 0.0;
  every_pixel.floor_margin = 0;
  every_pixel.line_width_factor = 0.0;
  const follow_bot::LineDetector lecture_equivalent(every_pixel);
  // The defaults: the noise specks that pass the colour box are mostly not yellower than the
  // floor by the floor test's margin, and those that are form weakly saturated blobs of their
  // own and are left out, so the centroid differs from the lecture's by their pull.
  const follow_bot::LineDetector defaults;

  int found = 0;
  double worst_difference = 0.0, worst_pull = 0.0;
  for (const cv::Mat& frame : frames) {
    const follow_bot::BandMeasurement band = lecture_equivalent.detect(frame).band;
    const double lecture_x = lectureCentroid(frame);
    if (band.pixel_count == 0 || lecture_x < 0) {
      if ((band.pixel_count == 0) != (lecture_x < 0)) {
        std::printf("disagreement: only one of the detectors found the line\n");
        return 1;
      }
      continue;
    }
    ++found;
    worst_difference = std::max(worst_difference, std::abs(band.centroid_x - lecture_x));
    worst_pull = std::max(worst_pull, std::abs(defaults.detect(frame).band.centroid_x - lecture_x));
  }
  std::printf(
      "%d frames %dx%d, line found in %d, max centroid difference %.2g px (defaults: %.2g px, "
      "the noise specks left out)\n",
      kFrames, kWidth, kHeight, found, worst_difference, worst_pull);
  if (worst_difference > 1e-9) return 1;

  const Stats lecture = timePerFrame(frames, lectureCentroid);
  auto time_detector = [&](const follow_bot::LineDetector& detector) {
    return timePerFrame(
        frames, [&](const cv::Mat& frame) { return detector.detect(frame).band.centroid_x; });
  };
  const Stats equivalent = time_detector(lecture_equivalent);
  const Stats ours = time_detector(defaults);
  std::printf("lecture  (cvtColor+inRange+row blanking+moments): median %8.1f us  p99 %8.1f us\n",
              lecture.median_us, lecture.p99_us);
  std::printf("LineDetector, every pixel (band only, fused pass): median %8.1f us  p99 %8.1f us\n",
              equivalent.median_us, equivalent.p99_us);
  std::printf("LineDetector, defaults (+ floor test, blob rules):  median %8.1f us  p99 %8.1f us\n",
              ours.median_us, ours.p99_us);
  std::printf("speed-up of the defaults: median %.0fx  p99 %.0fx\n",
              lecture.median_us / ours.median_us, lecture.p99_us / ours.p99_us);
  return 0;
}
