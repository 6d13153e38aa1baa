// Beacon chaser: Lab 5's "follow green, stop at red" and the lecture's "approach the dumpster and
// stop 1 m in front of it", as one nodelet. One camera frame in, one status out; a Twist while
// it searches or approaches, silence while it stands still.
//
// Thin wiring around ColourBlobDetector and BeaconController; BehaviourNodelet adds the camera
// topics, frame checks, limits, the frame watchdog and the final stop. Thresholds and gains are
// ~params, also live through dynamic_reconfigure (cfg/BeaconChaser.cfg).
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <std_msgs/Bool.h>
#include <opencv2/imgproc.hpp>

#include "follow_bot/BeaconChaserConfig.h"
#include "follow_bot/BeaconDetections.h"
#include "follow_bot/beacon_controller.h"
#include "follow_bot/colour_blobs.h"
#include "follow_bot/ros/nodelets.h"
#include "follow_bot_common/ros/behaviour_nodelet.h"

namespace follow_bot {

namespace {

// Everything dynamic_reconfigure can change, as core configurations.
struct Settings {
  ColourBlobConfig detector;
  BeaconControllerConfig controller;
};

// "~name must be red, green or blue, got 'x'" unless `colour` names a detectable colour.
void requireColourName(const std::string& name, const std::string& colour) {
  if (!parseColourName(colour)) {  // checked in every mode: a typo is a typo
    throw std::invalid_argument("~" + name + " must be red, green or blue, got '" + colour + "'");
  }
}

// The core configurations for `cfg`, on top of `base` for what only start-up sets (target
// object, camera). Throws std::invalid_argument naming the first bad value; used for the ~params
// at start-up and for every reconfiguration, so both are held to the same rules. Ranges are the
// .cfg's: readConfig checks them at start-up, the dynamic_reconfigure server clamps live updates.
Settings coreSettings(const BeaconChaserConfig& cfg, const BeaconControllerConfig& base) {
  Settings settings;
  ColourBlobConfig& detector = settings.detector;
  for (ColourSpec& colour : detector.colours) {
    colour.sensitivity = cfg.sensitivity;
    colour.s_min = cfg.s_min;
    colour.v_min = cfg.v_min;
  }
  detector.min_area = cfg.min_area;
  if (const std::string error = validate(detector); !error.empty()) {
    throw std::invalid_argument(error);
  }

  BeaconControllerConfig& controller = settings.controller;
  controller = base;
  const std::optional<BeaconMode> mode = parseBeaconMode(cfg.mode);
  if (!mode) {
    throw std::invalid_argument("~mode must be 'follow_green_stop_red' or 'approach', got '" +
                                cfg.mode + "'");
  }
  controller.mode = *mode;
  requireColourName("follow_colour", cfg.follow_colour);
  requireColourName("stop_colour", cfg.stop_colour);
  requireColourName("target_colour", cfg.target_colour);
  controller.follow_colour = cfg.follow_colour;
  controller.stop_colour = cfg.stop_colour;
  controller.target_colour = cfg.target_colour;
  controller.close_area = cfg.close_area;
  controller.stop_min_area = cfg.stop_min_area;
  controller.stop_release_delay = cfg.stop_release_delay;
  controller.approach_speed = cfg.approach_speed;
  controller.turn_gain = cfg.turn_gain;
  controller.stop_distance = cfg.stop_distance;
  controller.max_linear = cfg.max_linear;
  controller.k_range = cfg.k_range;
  controller.k_bearing = cfg.k_bearing;
  controller.max_angular = cfg.max_angular;
  controller.search_rate = cfg.search_rate;
  for (const std::string& error :
       {validate(controller), checkColoursDetected(controller, detector)}) {
    if (!error.empty()) throw std::invalid_argument(error);
  }
  return settings;
}

// What only start-up sets: the target object. Throws std::invalid_argument naming the first bad
// value.
BeaconControllerConfig readStartupConfig(const ros::NodeHandle& pnh) {
  BeaconControllerConfig controller;
  const std::string shape = param<std::string>(pnh, "target_shape", "box");
  const std::optional<BeaconShape> parsed_shape = parseBeaconShape(shape);
  if (!parsed_shape) {
    throw std::invalid_argument("~target_shape must be 'box' or 'sphere', got '" + shape + "'");
  }
  controller.target.shape = *parsed_shape;
  controller.target.size_m = positiveParam(pnh, "target_size", controller.target.size_m);
  return controller;
}

// Searching and approaching steer; the states that stand still (holding a stop, arrived, or
// lost in approach mode, which has nothing to follow) are idle.
bool steers(BeaconState state) {
  return state == BeaconState::kSearching || state == BeaconState::kApproaching;
}

}  // namespace

class BeaconChaserNodelet : public BehaviourNodelet<BeaconChaserConfig> {
 private:
  void setup(ros::NodeHandle&, ros::NodeHandle& pnh, const BeaconChaserConfig&) override {
    startup_ = readStartupConfig(pnh);
  }

  // New settings, or new intrinsics (ranges need them), start with fresh controller state (a new
  // mode must not inherit the old one's).
  void configure(const BeaconChaserConfig& config) override {
    startup_.camera = camera();
    settings_ = coreSettings(config, startup_);
    detector_ = std::make_unique<ColourBlobDetector>(settings_.detector);
    controller_ = std::make_unique<BeaconController>(settings_.controller);
  }

  void advertise(ros::NodeHandle&, ros::NodeHandle& pnh) override {
    detections_pub_ = pnh.advertise<BeaconDetections>("detections", 1);
    for (const ColourSpec& colour : settings_.detector.colours) {  // Lab 5 step 3: one flag each
      found_pubs_.push_back(pnh.advertise<std_msgs::Bool>(colour.name + "_found", 1));
    }
  }

  Decision step(const Frame& frame) override {
    blobs_ = detector_->detect(frame.image);
    Twist2D desired;
    if (settings_.controller.mode == BeaconMode::kApproach && !hasIntrinsics()) {
      NODELET_WARN_THROTTLE(2.0, "approach needs camera_info on %s for ranges: holding still",
                            cameraInfoTopic().c_str());
    } else {
      desired = controller_->update(blobs_, frame.time);
    }
    const BeaconState state = controller_->state();
    return {desired, steers(state), toString(state)};
  }

  void report(const Frame& frame, const Twist2D& sent) override {
    for (std::size_t i = 0; i < blobs_.colours.size() && i < found_pubs_.size(); ++i) {
      std_msgs::Bool found;
      found.data = blobs_.colours[i].found;
      found_pubs_[i].publish(found);
    }
    if (detections_pub_.getNumSubscribers() == 0) return;
    BeaconDetections out;
    out.header = frame.header;
    for (const ColourBlob& blob : blobs_.colours) {
      BeaconDetection detection;
      detection.colour = blob.name;
      detection.found = blob.found;
      detection.area = blob.area;
      detection.centroid_x = blob.centroid.x;
      detection.centroid_y = blob.centroid.y;
      detection.radius = blob.circle_radius;
      detection.range = std::numeric_limits<float>::quiet_NaN();
      if (blob.name == settings_.controller.target_colour && controller_->lastRange()) {
        detection.range = *controller_->lastRange();
      }
      out.detections.push_back(detection);
    }
    out.state = toString(controller_->state());
    out.linear = sent.linear;
    out.angular = sent.angular;
    detections_pub_.publish(out);
  }

  void drawDebug(cv::Mat& canvas) override {
    for (const ColourBlob& blob : blobs_.colours) {
      if (!blob.found) continue;
      cv::drawContours(canvas, std::vector<std::vector<cv::Point>>{blob.contour}, 0,
                       cv::Scalar(255, 255, 255), 2);
      cv::circle(canvas, blob.circle_centre, static_cast<int>(blob.circle_radius),
                 cv::Scalar(0, 255, 255), 1);
      cv::putText(canvas, blob.name, blob.bounding_box.tl() - cv::Point(0, 5),
                  cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(255, 255, 255), 2);
    }
  }

  BeaconControllerConfig startup_;  // what only start-up sets: the target and the camera
  Settings settings_;
  std::unique_ptr<ColourBlobDetector> detector_;
  std::unique_ptr<BeaconController> controller_;
  BlobResult blobs_;  // the last frame's
  ros::Publisher detections_pub_;
  std::vector<ros::Publisher> found_pubs_;
};

}  // namespace follow_bot

FOLLOW_BOT_EXPORT_NODELET(BeaconChaserNodelet)
