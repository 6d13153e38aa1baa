#include "messages.h"

#include <limits>

#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>

namespace follow_bot {

LineStatus lineStatus(const std_msgs::Header& header, const LineMeasurement& seen,
                      const std::string& state, const Twist2D& sent) {
  LineStatus out;
  out.header = header;
  out.found = seen.band.found;
  out.centroid_x = seen.band.centroid_x;
  out.centroid_y = seen.band.centroid_y;
  out.error = seen.band.error_normalised;
  out.confidence = seen.band.confidence;
  out.pixel_count = seen.band.pixel_count;
  out.state = state;
  out.linear = sent.linear;
  out.angular = sent.angular;
  return out;
}

BeaconDetections beaconDetections(const std_msgs::Header& header, const BlobResult& blobs,
                                  const std::string& target_colour,
                                  const std::optional<double>& target_range,
                                  const std::string& state, const Twist2D& sent) {
  BeaconDetections out;
  out.header = header;
  for (const ColourBlob& blob : blobs.colours) {
    BeaconDetection detection;
    detection.colour = blob.name;
    detection.found = blob.found;
    detection.area = blob.area;
    detection.centroid_x = blob.centroid.x;
    detection.centroid_y = blob.centroid.y;
    detection.radius = blob.circle_radius;
    detection.range = std::numeric_limits<float>::quiet_NaN();
    if (blob.name == target_colour && target_range) detection.range = *target_range;
    out.detections.push_back(detection);
  }
  out.state = state;
  out.linear = sent.linear;
  out.angular = sent.angular;
  return out;
}

geometry_msgs::PoseStamped markerPose(const std_msgs::Header& header,
                                      const MarkerObservation& marker) {
  geometry_msgs::PoseStamped pose;
  pose.header = header;
  pose.pose.position.x = marker.translation[0];
  pose.pose.position.y = marker.translation[1];
  pose.pose.position.z = marker.translation[2];
  const cv::Matx33d& r = marker.rotation;
  tf2::Quaternion q;
  tf2::Matrix3x3(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2))
      .getRotation(q);
  pose.pose.orientation.w = q.w();
  pose.pose.orientation.x = q.x();
  pose.pose.orientation.y = q.y();
  pose.pose.orientation.z = q.z();
  return pose;
}

geometry_msgs::TransformStamped markerTransform(const geometry_msgs::PoseStamped& pose,
                                                const std::string& marker_frame) {
  geometry_msgs::TransformStamped transform;
  transform.header = pose.header;
  transform.child_frame_id = marker_frame;
  transform.transform.translation.x = pose.pose.position.x;
  transform.transform.translation.y = pose.pose.position.y;
  transform.transform.translation.z = pose.pose.position.z;
  transform.transform.rotation = pose.pose.orientation;
  return transform;
}

}  // namespace follow_bot
