#include "settings.h"

#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include "follow_bot/BeaconTargetDefaults.h"
#include "follow_bot/common.h"
#include "follow_bot/sign_detector.h"
#include "follow_bot/tag_detector.h"
#include "follow_bot_common/ros/config_mapping.h"
#include "follow_bot_common/ros/params.h"

namespace follow_bot {

namespace {

// "~name must be red, green or blue, got 'x'" unless `colour` names a detectable colour.
std::string colourName(const std::string& name, const std::string& colour) {
  parseChoice(name, colour, parseColourName, "red, green or blue");
  return colour;
}

// The core's message names its field ("family must be ..."); the user typed ~tag_family.
std::string tagError(const std::string& error) { return "~tag_" + error; }

}  // namespace

FollowerSettings followerSettings(const FollowerConfig& cfg) {
  FollowerSettings settings;
  LineDetectorConfig& detector = settings.detector;
  detector.lower = {cfg.h_min, cfg.s_min, cfg.v_min};
  detector.upper = {cfg.h_max, cfg.s_max, cfg.v_max};
  detector.band = {cfg.band_distance, cfg.band_rows};
  detector.look_ahead = {cfg.look_ahead_distance, cfg.band_rows};
  assignFromConfig(detector, cfg);

  SteeringConfig& steering = settings.steering;
  steering.mode = parseChoice("mode", cfg.mode, parseSteeringMode, "'lecture', 'pd' or 'path'");
  assignFromConfig(steering, cfg);
  assignFromConfig(steering.pd, cfg);
  assignFromConfig(steering.search, cfg);
  assignFromConfig(steering.path, cfg);
  settings.estimate_latency = cfg.estimate_latency;
  requireValid({validate(detector), validate(steering)});
  return settings;
}

BeaconChaserSettings beaconChaserSettings(const BeaconChaserConfig& cfg,
                                          const BeaconControllerConfig& startup) {
  BeaconChaserSettings settings;
  ColourBlobConfig& detector = settings.detector;
  for (ColourSpec& colour : detector.colours) {
    colour.sensitivity = cfg.sensitivity;
    colour.s_min = cfg.s_min;
    colour.v_min = cfg.v_min;
  }
  assignFromConfig(detector, cfg);
  const BeaconMode mode =
      parseChoice("mode", cfg.mode, parseBeaconMode, "'follow_green_stop_red' or 'approach'");
  // Lab 5's beacons are balls; an approached box is not round.
  const bool box_target =
      mode == BeaconMode::kApproach && startup.target.shape == BeaconShape::kBox;
  detector.roundness_tolerance = box_target ? 0.0 : cfg.roundness_tolerance;
  // Balls rest on the floor: follow mode's are ~ball_radius, an approached sphere is the target.
  const double ball_radius =
      mode == BeaconMode::kApproach ? (box_target ? 0.0 : startup.target.size_m) : cfg.ball_radius;
  if (ball_radius > 0.0) {
    detector.floor_ball =
        ColourBlobConfig::FloorBall{ball_radius, cfg.ball_size_tolerance, startup.camera};
  }
  requireValid({validate(detector)});

  BeaconControllerConfig& controller = settings.controller;
  controller = startup;
  controller.mode = mode;
  // Checked in every mode: a typo is a typo.
  controller.follow_colour = colourName("follow_colour", cfg.follow_colour);
  controller.stop_colour = colourName("stop_colour", cfg.stop_colour);
  controller.target_colour = colourName("target_colour", cfg.target_colour);
  assignFromConfig(controller, cfg);
  requireValid({validate(controller), checkColoursDetected(controller, detector)});
  return settings;
}

BeaconControllerConfig beaconStartupConfig(const ros::NodeHandle& pnh) {
  BeaconControllerConfig controller;
  controller.target.shape = parseChoice(
      "target_shape", param<std::string>(pnh, "target_shape", BeaconTargetDefaults::target_shape),
      parseBeaconShape, "'box' or 'sphere'");
  controller.target.size_m = positiveParam(pnh, "target_size", controller.target.size_m);
  controller.target.depth_m = positiveParam(pnh, "target_depth", controller.target.depth_m);
  return controller;
}

std::unique_ptr<MarkerDetector> makeMarkerDetector(const ParkerConfig& cfg) {
  if (cfg.target == "apriltag") {
    TagDetectorConfig config;
    assignFromConfig(config, cfg);
    if (const std::string error = validate(config); !error.empty()) {
      throw std::invalid_argument(tagError(error));
    }
    try {
      return std::make_unique<TagDetector>(config);  // throws on an id the family lacks
    } catch (const std::invalid_argument& error) {
      throw std::invalid_argument(tagError(error.what()));
    }
  }
  if (cfg.target == "sign") {
    SignDetectorConfig config;
    assignFromConfig(config, cfg);
    if (config.image_path.empty()) {
      throw std::invalid_argument("~sign_image must name the sign's reference image file");
    }
    try {
      return std::make_unique<SignDetector>(config);  // throws on a missing/featureless image
    } catch (const std::invalid_argument& error) {
      throw std::invalid_argument(std::string("~sign_image: ") + error.what());
    }
  }
  throw std::invalid_argument("~target must be 'apriltag' or 'sign', got '" + cfg.target + "'");
}

ParkingServoConfig parkingServoConfig(const ParkerConfig& cfg, const CameraGeometry& camera) {
  ParkingServoConfig config;
  assignFromConfig(config, cfg);
  config.camera = camera;
  if (config.standoff_m - camera.x_offset_m <= 0.05) {
    std::ostringstream error;
    error << "~standoff must exceed ~camera_x_offset + 0.05 m (the marker > 5 cm in front of the "
             "camera), got "
          << config.standoff_m << " with ~camera_x_offset " << camera.x_offset_m;
    throw std::invalid_argument(error.str());
  }
  // Anything else validate() rejects is outside the .cfg's ranges: a bug, not a user error.
  if (const std::string error = validate(config); !error.empty()) {
    throw std::logic_error("parking servo: " + error);
  }
  return config;
}

PanoramaSessionConfig panoramaSettings(const PanoramaConfig& cfg,
                                       const image_converter::MatchingConfig& matching) {
  requireLinked(cfg.step_angle_deg <= cfg.total_angle_deg,
                "~step_angle_deg must be at most ~total_angle_deg", cfg.step_angle_deg,
                cfg.total_angle_deg);
  requireLinked(cfg.min_angular <= cfg.max_angular, "~min_angular must be at most ~max_angular",
                cfg.min_angular, cfg.max_angular);
  requireLinked(cfg.yaw_tolerance_deg < cfg.step_angle_deg / 2.0,
                "~yaw_tolerance_deg must be below ~step_angle_deg / 2", cfg.yaw_tolerance_deg,
                cfg.step_angle_deg);
  PanoramaSessionConfig settings;
  assignFromConfig(settings.capture, cfg);

  settings.match.detector =
      parseChoice("detector", matching.detector, image_converter::parseDetector, "orb or sift");
  assignFromConfig(settings.match, matching);
  settings.method = parseChoice("stitch_method", cfg.stitch_method, parseStitchMethod,
                                "auto, features or rotation");
  assignFromConfig(settings, cfg);
  return settings;
}

}  // namespace follow_bot
