// Synthetic scenes and camera views with exactly known geometry, for the stitching tests.
#pragma once

#include <cmath>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace image_converter::testing {

// A busy, deterministic texture (shapes of random colour on smoothed noise) with enough corners
// for ORB and SIFT everywhere; a light blur keeps resampling errors small.
inline cv::Mat texturedScene(const cv::Size& size, unsigned seed) {
  cv::RNG rng(seed);
  cv::Mat scene(size, CV_8UC3);
  rng.fill(scene, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(scene, scene, cv::Size(0, 0), 2.0);
  const int shapes = size.area() / 1500;
  for (int i = 0; i < shapes; ++i) {
    const cv::Scalar colour(rng.uniform(0, 256), rng.uniform(0, 256), rng.uniform(0, 256));
    const cv::Point centre(rng.uniform(0, size.width), rng.uniform(0, size.height));
    const int extent = rng.uniform(4, 30);
    if (i % 2 == 0) {
      cv::rectangle(scene, centre, centre + cv::Point(extent, rng.uniform(4, 30)), colour,
                    cv::FILLED);
    } else {
      cv::circle(scene, centre, extent / 2, colour, cv::FILLED, cv::LINE_AA);
    }
  }
  cv::GaussianBlur(scene, scene, cv::Size(0, 0), 1.0);
  return scene;
}

// The view of a pinhole camera (focal f, principal point at the centre of `view_size`) at the
// centre of a cylinder of radius f whose unrolled surface is `cylinder`, turned left by `yaw`
// rad from the direction of the cylinder's centre column. Cylinder pixel (u, v) is the ray at
// azimuth (u - cols/2) / f (right positive) and height (v - rows/2) / f.
inline cv::Mat cylinderView(const cv::Mat& cylinder, double f, const cv::Size& view_size,
                            double yaw) {
  cv::Mat map_x(view_size, CV_32F), map_y(view_size, CV_32F);
  const double c = std::cos(yaw), s = std::sin(yaw);
  for (int v = 0; v < view_size.height; ++v) {
    for (int u = 0; u < view_size.width; ++u) {
      const double x = (u - view_size.width / 2.0) / f, y = (v - view_size.height / 2.0) / f;
      // Turning left swings the optical axis towards -x of the reference view.
      const double wx = c * x - s, wz = s * x + c;
      map_x.at<float>(v, u) = static_cast<float>(f * std::atan2(wx, wz) + cylinder.cols / 2.0);
      map_y.at<float>(v, u) = static_cast<float>(f * y / std::hypot(wx, wz) + cylinder.rows / 2.0);
    }
  }
  cv::Mat view;
  cv::remap(cylinder, view, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return view;
}

}  // namespace image_converter::testing
