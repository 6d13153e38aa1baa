#include "follow_bot_common/ros/rviz_markers.h"

#include <utility>

namespace follow_bot_common {

namespace {

geometry_msgs::Point point(double x, double y, double z) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

}  // namespace

std_msgs::ColorRGBA rgba(double red, double green, double blue, double alpha) {
  std_msgs::ColorRGBA colour;
  colour.r = static_cast<float>(red);
  colour.g = static_cast<float>(green);
  colour.b = static_cast<float>(blue);
  colour.a = static_cast<float>(alpha);
  return colour;
}

RvizMarkers::RvizMarkers(std_msgs::Header header) : header_(std::move(header)) {
  visualization_msgs::Marker clear;
  clear.header = header_;
  clear.action = visualization_msgs::Marker::DELETEALL;
  array_.markers.push_back(clear);
}

visualization_msgs::Marker& RvizMarkers::add(const std::string& ns, int id, int type,
                                             const std_msgs::ColorRGBA& colour) {
  visualization_msgs::Marker& marker = array_.markers.emplace_back();
  marker.header = header_;
  marker.ns = ns;
  marker.id = id;
  marker.type = type;
  marker.action = visualization_msgs::Marker::ADD;
  marker.pose.orientation.w = 1.0;
  marker.color = colour;
  return marker;
}

void RvizMarkers::floorPoints(const std::string& ns, const std::vector<cv::Point2d>& points,
                              const std_msgs::ColorRGBA& colour, double diameter_m) {
  if (points.empty()) return;
  visualization_msgs::Marker& marker = add(ns, 0, visualization_msgs::Marker::SPHERE_LIST, colour);
  marker.scale.x = marker.scale.y = marker.scale.z = diameter_m;
  for (const cv::Point2d& p : points) marker.points.push_back(point(p.x, p.y, 0.0));
}

void RvizMarkers::floorLine(const std::string& ns, const std::vector<cv::Point2d>& points,
                            const std_msgs::ColorRGBA& colour, double width_m) {
  if (points.size() < 2) return;
  visualization_msgs::Marker& marker = add(ns, 0, visualization_msgs::Marker::LINE_STRIP, colour);
  marker.scale.x = width_m;
  for (const cv::Point2d& p : points) marker.points.push_back(point(p.x, p.y, 0.0));
}

void RvizMarkers::sphere(const std::string& ns, int id, const cv::Point3d& centre,
                         double diameter_m, const std_msgs::ColorRGBA& colour) {
  visualization_msgs::Marker& marker = add(ns, id, visualization_msgs::Marker::SPHERE, colour);
  marker.pose.position = point(centre.x, centre.y, centre.z);
  marker.scale.x = marker.scale.y = marker.scale.z = diameter_m;
}

void RvizMarkers::arrow(const std::string& ns, int id, const cv::Point3d& start,
                        const cv::Vec3d& direction, double length_m,
                        const std_msgs::ColorRGBA& colour) {
  visualization_msgs::Marker& marker = add(ns, id, visualization_msgs::Marker::ARROW, colour);
  const cv::Vec3d along = cv::normalize(direction);
  marker.points.push_back(point(start.x, start.y, start.z));
  marker.points.push_back(point(start.x + length_m * along[0], start.y + length_m * along[1],
                                start.z + length_m * along[2]));
  marker.scale.x = 0.1 * length_m;  // shaft diameter
  marker.scale.y = 0.2 * length_m;  // head diameter
  marker.scale.z = 0.3 * length_m;  // head length
}

void RvizMarkers::text(const std::string& ns, int id, const cv::Point3d& position,
                       const std::string& text, double height_m,
                       const std_msgs::ColorRGBA& colour) {
  visualization_msgs::Marker& marker =
      add(ns, id, visualization_msgs::Marker::TEXT_VIEW_FACING, colour);
  marker.pose.position = point(position.x, position.y, position.z);
  marker.scale.z = height_m;
  marker.text = text;
}

}  // namespace follow_bot_common
