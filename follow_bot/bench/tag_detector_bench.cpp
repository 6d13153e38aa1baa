// Times follow_bot::TagDetector (libapriltag detection + decision-margin gate + IPPE pose with
// the ambiguity resolved) against a bare ViSP vpDetectorAprilTag::detect on the same synthetic
// 640x480 frames like the simulator's (tag36h11 at 0.5-3 m, face-on to 50 deg; noise-free, as
// the parking worlds: sensor noise on flat synthetic grey makes both detectors ~10x slower alike),
// one thread and the same quad decimation. Goal: median <= 3 ms per frame; on a near tag <= 1.1x
// the bare ViSP detect (small tags are fitted again, and a frame without the tag searched again,
// at full resolution: their cost is printed). Then the same frames through the turtlebot3 barrel
// lens against the pinhole ones.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <utility>
#include <vector>

#include <visp3/core/vpImage.h>
#include <visp3/detection/vpDetectorAprilTag.h>

#include "../test/synthetic_tag.h"
#include "follow_bot/tag_detector.h"

namespace {

constexpr int kFrames = 120;
constexpr int kRounds = 10;          // timed passes over all frames, after one untimed pass
constexpr double kNoiseSigma = 0.0;  // grey levels

std::vector<cv::Mat> makeFrames(const follow_bot_common::CameraGeometry& camera) {
  cv::RNG rng(7);
  std::vector<cv::Mat> frames;
  for (int i = 0; i < kFrames; ++i) {
    const double along = 0.5 + 2.5 * i / (kFrames - 1);
    const double right = 0.15 * along * std::sin(0.37 * i);
    const double incidence = 0.87 * std::sin(0.23 * i);  // up to 50 deg
    follow_bot::test::TagView view = follow_bot::test::viewFrom(along, right, 0.0);
    const double c = std::cos(incidence), s = std::sin(incidence);
    view.rotation = view.rotation * cv::Matx33d(c, 0, s, 0, 1, 0, -s, 0, c);
    cv::Mat gray(480, 640, CV_8UC1, cv::Scalar(120));
    // Some floor-like texture so the quad search has edges to reject.
    cv::rectangle(gray, cv::Rect(0, 300, 640, 180), cv::Scalar(95), cv::FILLED);
    follow_bot::test::drawTag(gray, camera, 0, 0.30, view.rotation, view.translation);
    cv::Mat noise(gray.size(), CV_16SC1);
    rng.fill(noise, cv::RNG::NORMAL, 0, kNoiseSigma);
    cv::Mat noisy;
    gray.convertTo(noisy, CV_16SC1);
    noisy += noise;
    noisy.convertTo(gray, CV_8UC1);
    frames.push_back(gray);
  }
  return frames;
}

// The harness's turtlebot3 lens on `camera` (P = K).
follow_bot_common::CameraGeometry throughLens(const follow_bot_common::CameraGeometry& camera) {
  follow_bot_common::CameraGeometry lensed = camera;
  const cv::Matx33d k(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  lensed.lens = follow_bot_common::CameraLens{k, {-0.28, 0.07, 0.0, 0.0, 0.0}, cv::Matx33d::eye()};
  return lensed;
}

// The pinhole frames as the lens images them: each raw pixel samples the rectified frame where
// rectifyPixels puts it.
std::vector<cv::Mat> distort(const std::vector<cv::Mat>& frames,
                             const follow_bot_common::CameraGeometry& lensed) {
  std::vector<cv::Point2f> raw;
  for (int v = 0; v < frames.front().rows; ++v) {
    for (int u = 0; u < frames.front().cols; ++u) raw.emplace_back(u, v);
  }
  const std::vector<cv::Point2f> rectified = follow_bot_common::rectifyPixels(lensed, raw);
  cv::Mat map(frames.front().size(), CV_32FC2);
  std::copy(rectified.begin(), rectified.end(), map.begin<cv::Point2f>());
  std::vector<cv::Mat> distorted;
  for (const cv::Mat& frame : frames) {
    distorted.emplace_back();
    cv::remap(frame, distorted.back(), map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  }
  return distorted;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

double msOf(const std::function<void()>& work) {
  const auto start = std::chrono::steady_clock::now();
  work();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

}  // namespace

int main() {
  cv::setNumThreads(1);
  follow_bot_common::CameraGeometry camera;
  camera.pitch_rad = 0.0;
  const std::vector<cv::Mat> frames = makeFrames(camera);
  std::vector<vpImage<unsigned char>> visp_frames;
  for (const cv::Mat& frame : frames) {
    visp_frames.emplace_back(frame.rows, frame.cols);
    std::copy(frame.datastart, frame.dataend, visp_frames.back().bitmap);
  }

  follow_bot::TagDetectorConfig config;
  follow_bot::TagDetector ours(config);
  vpDetectorAprilTag visp(vpDetectorAprilTag::TAG_36h11);
  visp.setAprilTagNbThreads(1);
  visp.setAprilTagQuadDecimate(static_cast<float>(config.quad_decimate));

  int found_ours = 0, found_visp = 0;
  for (int i = 0; i < kFrames; ++i) {
    found_ours += ours.detect(frames[i], camera) ? 1 : 0;
    found_visp += visp.detect(visp_frames[i]) ? 1 : 0;
  }
  // Frame by frame, one detector then the other, so drift in machine load hits both alike.
  std::vector<double> ms_ours, ms_visp;
  for (int round = 0; round < kRounds; ++round) {
    for (int i = 0; i < kFrames; ++i) {
      ms_ours.push_back(msOf([&] { ours.detect(frames[i], camera); }));
      ms_visp.push_back(msOf([&] { visp.detect(visp_frames[i]); }));
    }
  }
  const double ours_median = median(ms_ours);
  const double visp_median = median(ms_visp);
  std::printf("frames: %d (640x480, tag36h11 0.30 m at 0.5-3 m, 0-50 deg), quad_decimate %.1f\n",
              kFrames, config.quad_decimate);
  std::printf("  TagDetector detect+gate+pose  median %.3f ms  (found %d/%d)\n", ours_median,
              found_ours, kFrames);
  std::printf("  vpDetectorAprilTag::detect    median %.3f ms  (found %d/%d)\n", visp_median,
              found_visp, kFrames);
  std::printf("  ratio %.3f, median %.3f ms (goal <= 3 ms)\n", ours_median / visp_median,
              ours_median);

  // One frame at a time: a near tag (decimated search only), a small one (fitted again at full
  // resolution on its patch) and none (the frame searched again at full resolution).
  std::printf("  per frame, TagDetector / bare vpDetectorAprilTag::detect (median of %d):\n",
              kFrames * kRounds);
  for (const auto& [name, along] : {std::pair<const char*, double>{"near tag 0.5 m", 0.5},
                                    {"small tag 3 m", 3.0},
                                    {"no tag", -1.0}}) {
    cv::Mat gray(480, 640, CV_8UC1, cv::Scalar(120));
    cv::rectangle(gray, cv::Rect(0, 300, 640, 180), cv::Scalar(95), cv::FILLED);
    if (along > 0) {
      const follow_bot::test::TagView view = follow_bot::test::viewFrom(along, 0.0, 0.0);
      follow_bot::test::drawTag(gray, camera, 0, 0.30, view.rotation, view.translation);
    }
    vpImage<unsigned char> visp_gray(gray.rows, gray.cols);
    std::copy(gray.datastart, gray.dataend, visp_gray.bitmap);
    std::vector<double> ms_one, ms_bare;
    for (int i = 0; i < kFrames * kRounds; ++i) {
      ms_one.push_back(msOf([&] { ours.detect(gray, camera); }));
      ms_bare.push_back(msOf([&] { visp.detect(visp_gray); }));
    }
    std::printf("    %-15s %.3f / %.3f ms  ratio %.2f\n", name, median(ms_one), median(ms_bare),
                median(ms_one) / median(ms_bare));
  }

  // Raw frames through the turtlebot3 lens (the detector refits each tag on its rectified patch)
  // against the pinhole frames, frame by frame in turn.
  const follow_bot_common::CameraGeometry lensed = throughLens(camera);
  const std::vector<cv::Mat> raw_frames = distort(frames, lensed);
  follow_bot::TagDetector through_lens(config);
  int found_lens = 0;
  for (int i = 0; i < kFrames; ++i)
    found_lens += through_lens.detect(raw_frames[i], lensed) ? 1 : 0;
  std::vector<double> ms_pinhole, ms_lens;
  for (int round = 0; round < kRounds; ++round) {
    for (int i = 0; i < kFrames; ++i) {
      ms_pinhole.push_back(msOf([&] { ours.detect(frames[i], camera); }));
      ms_lens.push_back(msOf([&] { through_lens.detect(raw_frames[i], lensed); }));
    }
  }
  std::printf(
      "  TagDetector on raw frames through the turtlebot3 lens  median %.3f ms (found %d/%d)\n"
      "  ... on the pinhole frames  median %.3f ms: lens / pinhole %.3f\n",
      median(ms_lens), found_lens, kFrames, median(ms_pinhole),
      median(ms_lens) / median(ms_pinhole));
  return 0;
}
