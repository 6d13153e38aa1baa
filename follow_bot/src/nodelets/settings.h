// The behaviours' .cfg values as their cores' configurations: one function per behaviour, used
// for the ~params at start-up and for every live update, so both are held to the same rules.
// Each throws std::invalid_argument naming the first bad ~param; the .cfg ranges are checked
// before (readConfig at start-up, the dynamic_reconfigure server's clamping live).
#pragma once

#include <memory>

#include <ros/node_handle.h>

#include "follow_bot/BeaconChaserConfig.h"
#include "follow_bot/FollowerConfig.h"
#include "follow_bot/FollowerDefaults.h"
#include "follow_bot/PanoramaConfig.h"
#include "follow_bot/ParkerConfig.h"
#include "follow_bot/beacon_controller.h"
#include "follow_bot/colour_blobs.h"
#include "follow_bot/line_detector.h"
#include "follow_bot/marker_target.h"
#include "follow_bot/panorama_session.h"
#include "follow_bot/parking_servo.h"
#include "follow_bot/steering_law.h"
#include "image_converter/MatchingConfig.h"

namespace follow_bot {

struct FollowerSettings {
  LineDetectorConfig detector;
  SteeringConfig steering;
  bool estimate_latency = FollowerDefaults::estimate_latency;  // with odometry (~use_odom)
};
FollowerSettings followerSettings(const FollowerConfig& cfg);

struct BeaconChaserSettings {
  ColourBlobConfig detector;
  BeaconControllerConfig controller;
};
// On top of `startup` for what only start-up sets (target object, camera).
BeaconChaserSettings beaconChaserSettings(const BeaconChaserConfig& cfg,
                                          const BeaconControllerConfig& startup);
// What only start-up sets: the target object (~target_shape, ~target_size, ~target_depth).
BeaconControllerConfig beaconStartupConfig(const ros::NodeHandle& pnh);

// The marker detector ~target names.
std::unique_ptr<MarkerDetector> makeMarkerDetector(const ParkerConfig& cfg);
ParkingServoConfig parkingServoConfig(const ParkerConfig& cfg, const CameraGeometry& camera);

// With the feature matching's ~params (image_converter's cfg/Matching.cfg).
PanoramaSessionConfig panoramaSettings(const PanoramaConfig& cfg,
                                       const image_converter::MatchingConfig& matching);

}  // namespace follow_bot
