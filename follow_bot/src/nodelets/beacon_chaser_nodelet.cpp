// Beacon chaser: Lab 5's "follow green, stop at red" and the lecture's "approach the dumpster and
// stop 1 m in front of it", as one nodelet. One camera frame in, one status out; a Twist while
// it searches or approaches, silence while it stands still.
//
// Thin wiring around ColourBlobDetector and BeaconController; BehaviourNodelet adds the camera
// topics, frame checks, limits, the frame watchdog and the final stop. Thresholds and gains are
// ~params, also live through dynamic_reconfigure (cfg/BeaconChaser.cfg).
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <vector>

#include <std_msgs/Bool.h>
#include <opencv2/imgproc.hpp>

#include "follow_bot/BeaconChaserConfig.h"
#include "follow_bot/common.h"
#include "follow_bot/ros/nodelets.h"
#include "follow_bot_common/ros/behaviour_nodelet.h"
#include "messages.h"
#include "settings.h"

namespace follow_bot {

namespace {

// Searching and approaching steer; the states that stand still (holding a stop, arrived, or
// lost in approach mode, which has nothing to follow) are idle.
bool steers(BeaconState state) {
  return state == BeaconState::kSearching || state == BeaconState::kApproaching;
}

// The colour a spec finds, fully saturated and bright, for rviz.
std_msgs::ColorRGBA displayColour(const ColourSpec& colour) {
  cv::Mat pixel(1, 1, CV_8UC3, cv::Scalar(colour.hue_centre, 255, 255));
  cv::cvtColor(pixel, pixel, cv::COLOR_HSV2RGB);
  const cv::Vec3b rgb = pixel.at<cv::Vec3b>(0, 0);
  return rgba(rgb[0] / 255.0, rgb[1] / 255.0, rgb[2] / 255.0);
}

std::string metres(double range) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f m", range);
  return text;
}

}  // namespace

class BeaconChaserNodelet : public BehaviourNodelet<BeaconChaserConfig> {
 private:
  void setup(ros::NodeHandle& /*nh*/, ros::NodeHandle& pnh,
             const BeaconChaserConfig& /*config*/) override {
    startup_ = beaconStartupConfig(pnh);
  }

  // New settings, or new intrinsics (ranges need them), start with fresh controller state (a new
  // mode must not inherit the old one's).
  void configure(const BeaconChaserConfig& config) override {
    startup_.camera = camera();
    settings_ = beaconChaserSettings(config, startup_);
    detector_ = std::make_unique<ColourBlobDetector>(settings_.detector);
    controller_ = std::make_unique<BeaconController>(settings_.controller);
  }

  void advertise(ros::NodeHandle& /*nh*/, ros::NodeHandle& pnh) override {
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
    // Red is a stop signal: the robot is told zero at once, not by the deceleration ramp.
    return {desired, steers(state), toString(state), state == BeaconState::kStoppedByRed};
  }

  void report(const Frame& frame, const Twist2D& sent) override {
    for (std::size_t i = 0; i < blobs_.colours.size() && i < found_pubs_.size(); ++i) {
      std_msgs::Bool found;
      found.data = blobs_.colours[i].found;
      found_pubs_[i].publish(found);
    }
    if (detections_pub_.getNumSubscribers() > 0) {
      detections_pub_.publish(
          beaconDetections(frame.header, blobs_, settings_.controller.target_colour,
                           controller_->lastRange(), toString(controller_->state()), sent));
    }
  }

  void drawDebug(cv::Mat& canvas) override { ColourBlobDetector::drawDebug(canvas, blobs_); }

  // Each ball in view where its circle puts it on the floor, with its range; in approach mode a
  // box target at the range and bearing the controller steers on. Ids: the colour's index.
  void addMarkers(RvizMarkers& markers) override {
    const std::optional<ColourBlobConfig::FloorBall>& ball = settings_.detector.floor_ball;
    const BeaconControllerConfig& controller = settings_.controller;
    for (std::size_t i = 0; i < blobs_.colours.size(); ++i) {
      const ColourBlob& blob = blobs_.colours[i];
      const std_msgs::ColorRGBA colour = displayColour(settings_.detector.colours[i]);
      const int id = static_cast<int>(i);
      if (ball) {
        const std::optional<cv::Point3d> centre =
            sphereCentre(blob, blobs_.image_width, blobs_.image_height, camera(), ball->radius_m);
        if (!centre) continue;
        markers.sphere("beacons", id, *centre, 2.0 * ball->radius_m, colour);
        const double range = std::hypot(centre->x, centre->y) - ball->radius_m;
        markers.text("ranges", id, *centre + cv::Point3d(0, 0, 2.0 * ball->radius_m),
                     blob.name + " " + metres(range), 0.1, colour);
      } else if (controller.mode == BeaconMode::kApproach &&
                 blob.name == controller.target_colour && controller_->lastRange() &&
                 controller_->lastBearing()) {
        const double range = *controller_->lastRange();
        const double bearing = *controller_->lastBearing();  // positive: right of the axis
        const cv::Point3d contact(range * std::cos(bearing), -range * std::sin(bearing), 0.0);
        markers.sphere("beacons", id, contact, 0.1, colour);
        markers.text("ranges", id, contact + cv::Point3d(0, 0, 0.3),
                     blob.name + " " + metres(range), 0.1, colour);
      }
    }
  }

  BeaconControllerConfig startup_;  // what only start-up sets: the target and the camera
  BeaconChaserSettings settings_;
  std::unique_ptr<ColourBlobDetector> detector_;
  std::unique_ptr<BeaconController> controller_;
  BlobResult blobs_;  // the last frame's
  ros::Publisher detections_pub_;
  std::vector<ros::Publisher> found_pubs_;
};

}  // namespace follow_bot

FOLLOW_BOT_EXPORT_NODELET(BeaconChaserNodelet)

follow_bot_common::NodeHelp follow_bot::beaconChaserHelp() {
  return behaviourHelp(
      "Chases coloured beacons: follows green and stops at red, or approaches one object to a "
      "set range (~mode).",
      {{"out", "~detections", "follow_bot/BeaconDetections",
        "the blobs per colour, state, command"},
       {"out", "~red_found", "std_msgs/Bool", "red in view (and ~green_found, ~blue_found)"},
       {"out", "~debug_image", "sensor_msgs/Image", "lazy: contours, circles, labels"},
       {"out", "~markers", "visualization_msgs/MarkerArray",
        "lazy, in ~base_frame: each beacon on the floor with its range"}});
}
