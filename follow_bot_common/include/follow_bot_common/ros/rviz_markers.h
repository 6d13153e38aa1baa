// What a behaviour believes, drawn for rviz: one visualization_msgs/MarkerArray per frame in the
// robot's base frame (x forward, y left, z up, the floor at z = 0), the behaviour's ~markers.
#pragma once

#include <string>
#include <vector>

#include <std_msgs/ColorRGBA.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>
#include <opencv2/core.hpp>

namespace follow_bot_common {

std_msgs::ColorRGBA rgba(double red, double green, double blue, double alpha = 1.0);

// One frame's markers. The array starts with a DELETEALL, so that whatever the last frame showed
// and this one does not (a band that lost the line, a beacon out of view) vanishes from rviz;
// each marker keeps its namespace and id from frame to frame.
class RvizMarkers {
 public:
  // `header`: the base frame and the camera frame's stamp.
  explicit RvizMarkers(std_msgs::Header header);

  // Small spheres on the floor, one per point.
  void floorPoints(const std::string& ns, const std::vector<cv::Point2d>& points,
                   const std_msgs::ColorRGBA& colour, double diameter_m);
  // A polyline on the floor (nothing for fewer than two points).
  void floorLine(const std::string& ns, const std::vector<cv::Point2d>& points,
                 const std_msgs::ColorRGBA& colour, double width_m);
  void sphere(const std::string& ns, int id, const cv::Point3d& centre, double diameter_m,
              const std_msgs::ColorRGBA& colour);
  // An arrow from `start`, `length_m` long along `direction`.
  void arrow(const std::string& ns, int id, const cv::Point3d& start, const cv::Vec3d& direction,
             double length_m, const std_msgs::ColorRGBA& colour);
  // Text facing the viewer, `height_m` high, centred on `position`.
  void text(const std::string& ns, int id, const cv::Point3d& position, const std::string& text,
            double height_m, const std_msgs::ColorRGBA& colour);

  const visualization_msgs::MarkerArray& message() const { return array_; }

 private:
  visualization_msgs::Marker& add(const std::string& ns, int id, int type,
                                  const std_msgs::ColorRGBA& colour);

  std_msgs::Header header_;
  visualization_msgs::MarkerArray array_;
};

}  // namespace follow_bot_common
