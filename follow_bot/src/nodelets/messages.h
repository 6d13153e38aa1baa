// The behaviours' own messages, filled from their cores' results for one frame.
#pragma once

#include <optional>
#include <string>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <std_msgs/Header.h>

#include "follow_bot/BeaconDetections.h"
#include "follow_bot/LineStatus.h"
#include "follow_bot/colour_blobs.h"
#include "follow_bot/common.h"
#include "follow_bot/line_detector.h"
#include "follow_bot/marker_target.h"
#include "follow_bot_common/velocity_limiter.h"

namespace follow_bot {

// The follower's ~line: the band's sighting, the state and the command sent.
LineStatus lineStatus(const std_msgs::Header& header, const LineMeasurement& seen,
                      const std::string& state, const Twist2D& sent);

// The beacon chaser's ~detections: every colour's blob, `target_range` (m) on the target's,
// the state and the command sent.
BeaconDetections beaconDetections(const std_msgs::Header& header, const BlobResult& blobs,
                                  const std::string& target_colour,
                                  const std::optional<double>& target_range,
                                  const std::string& state, const Twist2D& sent);

// The marker's pose in the camera optical frame (the header's), as a pose and as the transform
// to `marker_frame`.
geometry_msgs::PoseStamped markerPose(const std_msgs::Header& header,
                                      const MarkerObservation& marker);
geometry_msgs::TransformStamped markerTransform(const geometry_msgs::PoseStamped& pose,
                                                const std::string& marker_frame);

}  // namespace follow_bot
