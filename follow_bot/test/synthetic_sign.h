// Renders the parking sign at a known pose into a grey frame, for the sign detector's tests and
// benchmark: an exact plane homography K [r1 r2 t] of a mip level of the picture, sampled on a 4x
// finer grid and box-filtered down, on a grey background (what the harness renderer does).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "follow_bot/common.h"
#include "follow_bot_common/ground_projection.h"

namespace follow_bot::test {

constexpr double kSignWidthM = 0.40;  // worlds/parking_sign.yaml
constexpr int kSignFrameWidth = 640;
constexpr int kSignFrameHeight = 480;

// The sign `reference` (width kSignWidthM) with its frame (x right, y down, z into the sign) at
// `rotation`, `translation` in the optical frame; Gaussian noise of `noise_sigma` grey levels
// drawn from `noise_seed`.
inline cv::Mat renderSign(const cv::Mat& reference, const CameraGeometry& camera,
                          const cv::Matx33d& rotation, const cv::Vec3d& translation,
                          double noise_sigma = 0.0, uint64_t noise_seed = 12345,
                          cv::Size size = {kSignFrameWidth, kSignFrameHeight}) {
  constexpr int kSupersample = 4;
  const double projected_width = camera.fx * kSignWidthM / translation[2];
  cv::Mat level = reference;
  while (level.cols > projected_width * kSupersample && level.cols >= 32) {
    cv::resize(level, level, cv::Size(level.cols / 2, level.rows / 2), 0, 0, cv::INTER_AREA);
  }
  const double m = kSignWidthM / level.cols;  // metres per texel
  const double height = m * level.rows;
  const cv::Matx33d texel_to_plane(m, 0, 0.5 * m - kSignWidthM / 2, 0, m, 0.5 * m - height / 2, 0,
                                   0, 1);
  const cv::Matx33d k(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  const cv::Matx33d plane_to_image(rotation(0, 0), rotation(0, 1), translation[0], rotation(1, 0),
                                   rotation(1, 1), translation[1], rotation(2, 0), rotation(2, 1),
                                   translation[2]);
  // Fine sample f sits at coarse pixel (f + 0.5) / s - 0.5 (pixel centres at integers).
  const double s = kSupersample;
  const cv::Matx33d coarse_to_fine(s, 0, (s - 1) / 2, 0, s, (s - 1) / 2, 0, 0, 1);
  cv::Mat fine;
  cv::warpPerspective(level, fine, cv::Mat(coarse_to_fine * k * plane_to_image * texel_to_plane),
                      size * kSupersample, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(128));
  cv::Mat frame;
  cv::resize(fine, frame, size, 0, 0, cv::INTER_AREA);
  if (noise_sigma > 0.0) {
    cv::Mat noise(frame.size(), CV_32F);
    cv::RNG rng(noise_seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_sigma);
    frame.convertTo(frame, CV_32F);
    frame += noise;
    frame.convertTo(frame, CV_8U);
  }
  return frame;
}

inline cv::Matx33d rotationY(double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c, 0, s, 0, 1, 0, -s, 0, c};
}

inline cv::Matx33d rotationX(double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {1, 0, 0, 0, c, -s, 0, s, c};
}

// Angle of the rotation between a and b, radians.
inline double angleBetween(const cv::Matx33d& a, const cv::Matx33d& b) {
  const double c = (cv::trace(a.t() * b) - 1.0) / 2.0;
  return std::acos(std::max(-1.0, std::min(1.0, c)));
}

}  // namespace follow_bot::test
