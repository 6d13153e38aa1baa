#include "settings.h"

#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include "follow_bot/sign_detector.h"
#include "follow_bot/tag_detector.h"
#include "follow_bot_common/ros/config_mapping.h"
#include "follow_bot_common/ros/params.h"

namespace follow_bot {

namespace {

constexpr double kDegToRad = M_PI / 180.0;

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
  detector.look_ahead_enabled = cfg.look_ahead;
  detector.look_ahead = {cfg.look_ahead_distance, cfg.band_rows};
  detector.min_pixels = cfg.min_pixels;
  detector.blob_saturation_fraction = cfg.blob_saturation_fraction;
  detector.floor_margin = cfg.floor_margin;
  detector.floor_mads = cfg.floor_mads;
  detector.line_width_m = cfg.line_width;
  detector.line_width_factor = cfg.line_width_factor;

  SteeringConfig& steering = settings.steering;
  steering.mode = parseChoice("mode", cfg.mode, parseSteeringMode, "'lecture', 'pd' or 'path'");
  steering.max_linear = cfg.max_linear;
  steering.min_linear = cfg.min_linear;
  steering.max_angular = cfg.max_angular;
  steering.pd.kp = cfg.kp;
  steering.pd.kd = cfg.kd;
  steering.pd.taper = cfg.taper;
  steering.pd.look_ahead_weight = cfg.look_ahead_weight;
  steering.search.search_rate = cfg.search_rate;
  steering.path.heading_gain = cfg.heading_gain;
  steering.path.lateral_gain = cfg.lateral_gain;
  steering.path.command_latency = cfg.command_latency;
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
  detector.min_area = cfg.min_area;
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
  controller.close_area = cfg.close_area;
  controller.stop_min_area = cfg.stop_min_area;
  controller.stop_release_delay = cfg.stop_release_delay;
  controller.approach_speed = cfg.approach_speed;
  controller.approach_taper = cfg.approach_taper;
  controller.creep_speed = cfg.creep_speed;
  controller.turn_gain = cfg.turn_gain;
  controller.stop_distance = cfg.stop_distance;
  controller.max_linear = cfg.max_linear;
  controller.k_range = cfg.k_range;
  controller.k_bearing = cfg.k_bearing;
  controller.max_angular = cfg.max_angular;
  controller.search_rate = cfg.search_rate;
  requireValid({validate(controller), checkColoursDetected(controller, detector)});
  return settings;
}

BeaconControllerConfig beaconStartupConfig(const ros::NodeHandle& pnh) {
  BeaconControllerConfig controller;
  controller.target.shape =
      parseChoice("target_shape", param<std::string>(pnh, "target_shape", "box"), parseBeaconShape,
                  "'box' or 'sphere'");
  controller.target.size_m = positiveParam(pnh, "target_size", controller.target.size_m);
  controller.target.depth_m = positiveParam(pnh, "target_depth", controller.target.depth_m);
  return controller;
}

std::unique_ptr<MarkerDetector> makeMarkerDetector(const ParkerConfig& cfg) {
  if (cfg.target == "apriltag") {
    TagDetectorConfig config;
    config.family = cfg.tag_family;
    config.id = cfg.tag_id;
    config.size_m = cfg.tag_size;
    config.quad_decimate = cfg.quad_decimate;
    config.full_resolution_below = cfg.full_resolution_below;
    config.min_decision_margin = cfg.min_decision_margin;
    config.max_hamming = cfg.max_hamming;
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
    config.image_path = cfg.sign_image;
    config.width_m = cfg.sign_width;
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
  config.standoff_m = cfg.standoff;
  config.gain = cfg.gain;
  config.steer_gain = cfg.steer_gain;
  config.max_bearing_rad = cfg.max_bearing_deg * kDegToRad;
  config.backoff_m = cfg.backoff;
  config.max_linear = cfg.max_linear;
  config.max_angular = cfg.max_angular;
  config.search_rate = cfg.search_rate;
  config.search_step_rad = cfg.search_step_deg * kDegToRad;
  config.search_pause = cfg.search_pause;
  config.lost_timeout = cfg.lost_timeout;
  config.position_tolerance = cfg.position_tolerance;
  config.lateral_tolerance = cfg.lateral_tolerance;
  config.heading_tolerance_rad = cfg.heading_tolerance_deg * kDegToRad;
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
  PanoramaCaptureConfig& capture = settings.capture;
  capture.total_angle = cfg.total_angle_deg * M_PI / 180.0;
  capture.step_angle = cfg.step_angle_deg * M_PI / 180.0;
  capture.max_turn_rate = cfg.max_angular;
  capture.min_turn_rate = cfg.min_angular;
  capture.yaw_gain = cfg.yaw_gain;
  capture.yaw_tolerance = cfg.yaw_tolerance_deg * M_PI / 180.0;
  capture.settle_frames = cfg.settle_frames;
  capture.return_to_start = cfg.return_to_start;

  settings.match.detector = parseChoice(
      "detector", matching.detector,
      [](const std::string& name) {
        image_converter::Detector detector;
        return image_converter::parseDetector(name, detector) ? std::optional(detector)
                                                              : std::nullopt;
      },
      "orb or sift");
  settings.match.min_inliers = matching.min_inliers;
  settings.method = parseChoice("stitch_method", cfg.stitch_method, parseStitchMethod,
                                "auto, features or rotation");
  settings.frame_timeout = cfg.frame_timeout;
  settings.capture_timeout = cfg.capture_timeout;
  return settings;
}

}  // namespace follow_bot
