// Renders an AprilTag (Debian libapriltag's bitmap) at a known pose into a grey frame, for the
// detector's tests and benchmark: 4x4 supersampling, pixel centres at integer coordinates
// (OpenCV), a white margin of a quarter tag around the black square as in the harness worlds.
#pragma once

#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

extern "C" {
#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>
}

#include "follow_bot/common.h"
#include "follow_bot_common/ground_projection.h"

namespace follow_bot::test {

// Draws tag36h11 `id` whose black square has edge `size_m`, marker frame (x right, y down,
// z into the tag) at rotation `rotation` and translation `translation` in the optical frame.
inline void drawTag(cv::Mat& gray, const CameraGeometry& camera, int id, double size_m,
                    const cv::Matx33d& rotation, const cv::Vec3d& translation, int black = 0,
                    int white = 255) {
  apriltag_family_t* family = tag36h11_create();
  image_u8_t* bitmap = apriltag_to_image(family, id);
  const int cells = bitmap->width + 2;  // one more white cell each side: margin = size / 4
  const double cell_m = size_m / family->width_at_border;
  constexpr int kPxPerCell = 16;
  cv::Mat tag(cells * kPxPerCell, cells * kPxPerCell, CV_8UC1, cv::Scalar(white));
  for (int r = 0; r < bitmap->height; ++r) {
    for (int c = 0; c < bitmap->width; ++c) {
      const bool is_white = bitmap->buf[r * bitmap->stride + c] > 127;
      tag(cv::Rect((c + 1) * kPxPerCell, (r + 1) * kPxPerCell, kPxPerCell, kPxPerCell)) =
          is_white ? white : black;
    }
  }
  image_u8_destroy(bitmap);
  tag36h11_destroy(family);

  constexpr int kSuper = 4;
  // Bitmap pixel (u, v), centre convention -> marker plane (X, Y, 1).
  const double scale = cell_m / kPxPerCell;
  const double offset = -cells * cell_m / 2.0 + 0.5 * scale;
  const cv::Matx33d plane_from_bitmap(scale, 0, offset, 0, scale, offset, 0, 0, 1);
  const cv::Matx33d image_from_plane =
      cv::Matx33d(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1) *
      cv::Matx33d(rotation(0, 0), rotation(0, 1), translation[0], rotation(1, 0), rotation(1, 1),
                  translation[1], rotation(2, 0), rotation(2, 1), translation[2]);
  const double shift = (kSuper - 1) / 2.0;
  const cv::Matx33d super_from_image(kSuper, 0, shift, 0, kSuper, shift, 0, 0, 1);
  const cv::Matx33d homography = super_from_image * image_from_plane * plane_from_bitmap;

  cv::Mat super;
  cv::resize(gray, super, gray.size() * kSuper, 0, 0, cv::INTER_NEAREST);
  cv::Mat mask(tag.size(), CV_8UC1, cv::Scalar(255));
  cv::Mat warped, warped_mask;
  cv::warpPerspective(tag, warped, cv::Mat(homography), super.size(), cv::INTER_LINEAR,
                      cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::warpPerspective(mask, warped_mask, cv::Mat(homography), super.size(), cv::INTER_NEAREST,
                      cv::BORDER_CONSTANT, cv::Scalar(0));
  warped.copyTo(super, warped_mask);
  cv::resize(super, gray, gray.size(), 0, 0, cv::INTER_AREA);
}

// The tag seen from (distance along its normal, lateral offset to the tag's right, yaw of the
// camera about its y axis, radians): the camera at the tag's height looking along -normal,
// turned by `yaw` (positive turns the view to the right).
struct TagView {
  cv::Matx33d rotation;
  cv::Vec3d translation;
};

inline TagView viewFrom(double along, double right, double yaw) {
  // Camera position in the marker frame: in front (-z), `right` along +x.
  const cv::Vec3d camera_in_marker(right, 0, -along);
  // Camera axes in the marker frame before the yaw: x = marker x, y = marker y, z = marker z.
  const double c = std::cos(yaw), s = std::sin(yaw);
  const cv::Matx33d marker_from_camera(c, 0, s, 0, 1, 0, -s, 0, c);
  TagView view;
  view.rotation = marker_from_camera.t();
  view.translation = -(view.rotation * camera_in_marker);
  return view;
}

}  // namespace follow_bot::test
