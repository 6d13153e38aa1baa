// The camera-driven behaviour nodelet: what every behaviour does between its camera topics, its
// ~params and cmd_vel, so that a behaviour supplies only its cores and one step per frame.
#pragma once

#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <cv_bridge/cv_bridge.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <boost/thread/recursive_mutex.hpp>

#include "follow_bot_common/CameraDefaults.h"
#include "follow_bot_common/camera_mounting.h"
#include "follow_bot_common/ground_projection.h"
#include "follow_bot_common/ros/camera_input.h"
#include "follow_bot_common/ros/camera_mounting_source.h"
#include "follow_bot_common/ros/checked_nodelet.h"
#include "follow_bot_common/ros/command_output.h"
#include "follow_bot_common/ros/intrinsics_source.h"
#include "follow_bot_common/ros/node_help.h"
#include "follow_bot_common/ros/params.h"
#include "follow_bot_common/ros/rviz_markers.h"
#include "follow_bot_common/ros/topics.h"
#include "follow_bot_common/status_report.h"

namespace follow_bot_common {

// A behaviour node's --help: `summary`, the topics every behaviour has (camera in, the
// CommandOutput's), then its `own` (its debug image included, when it has one).
inline NodeHelp behaviourHelp(const std::string& summary, const std::vector<TopicHelp>& own) {
  NodeHelp help{
      summary,
      {{"in", topics::kImage, "sensor_msgs/Image",
        "image_transport, queue 1; ~image_transport (e.g. compressed) picks the transport"},
       {"in", topics::kCameraInfo, "sensor_msgs/CameraInfo", "the lens' intrinsics"},
       {"out", "cmd_vel", "geometry_msgs/Twist",
        "one per processed frame while it steers, limited; one zero when it stops"},
       {"out", "~status", "follow_bot_msgs/BehaviourStatus", "one per processed frame"},
       {"service", "~enable", "std_srvs/SetBool", "false: one zero Twist, then quiet"},
       {"out", "/diagnostics", "diagnostic_msgs/DiagnosticArray", "frame rate, behaviour state"}}};
  help.topics.insert(help.topics.end(), own.begin(), own.end());
  return help;
}

// One accepted camera frame.
struct Frame {
  const std_msgs::Header& header;
  const cv::Mat& image;  // BGR8, a view of the message: read only
  double time;           // s: the stamp, or now when it has none (CommandOutput::frameTime)
};

// A frame's decision (docs/behaviour_contract.md): the desired command before the limits,
// whether the behaviour steers (active) or not (idle), its state's name, and whether it halts:
// idle at once, the robot told zero past the deceleration bound (a stop signal in view).
struct Decision {
  Twist2D desired;
  bool active = true;
  std::string state;
  bool halt = false;
};

// What differs between the behaviours in the shared wiring.
struct BehaviourOptions {
  bool allow_reverse = false;    // CommandOutput may command negative linear speeds
  bool live_reconfigure = true;  // a dynamic_reconfigure server on the ~params
  bool debug_image = true;       // a ~debug_image topic, drawn only while someone listens
  bool markers = true;           // a ~markers topic, built only while someone listens
};

// The nodelet of a behaviour driven by camera frames (`Config`: its generated dynamic_reconfigure
// config). It owns:
//  * start-up: the ~params read and checked against the .cfg (readConfig), the camera's mounting
//    ~params (readCameraMounting: ~camera_height, ~camera_pitch_deg, ~camera_x_offset over
//    CameraGeometry's defaults, the same for every behaviour) and where the mounting comes from
//    (CameraMountingSource: ~camera_mounting tf|params, ~base_frame, ~mounting_timeout), then
//    setup() and
//    configure(); with live_reconfigure, a dynamic_reconfigure server whose updates go through
//    the same configure(): a value outside its .cfg range is clamped with a warning naming it, a
//    rejected update changes nothing and the server reports back the settings in force. Any
//    start-up error names the ~param and fails the load; a ~param the node does not read is
//    warned about (CheckedNodelet).
//  * `camera/rgb/camera_info` (queue 1; names relative to the namespace, follow_bot_common/ros/
//    topics.h): usable intrinsics go into camera(), fitted to the frames' size
//    (IntrinsicsSource; ~image_rectified: the frames are image_rect, D is not applied);
//    unusable ones are ignored with a throttled error. A separate subscription, not a
//    CameraSubscriber: a behaviour keeps running on frames when camera_info is late or missing
//    (then it says what it cannot do). A camera_info that does not describe the frames while
//    the intrinsics in force do gets a throttled warning; a frame that neither describes is
//    dropped with a throttled error naming both sizes.
//  * `camera/rgb/image_raw` (image_transport, queue 1): frame acceptance (encoding, size, step,
//    stamp checks; a bad frame is dropped with a throttled error; every frame and camera_info
//    counted under its outcome in the diagnostics, CommandOutput::frameHandled), the camera's
//    mounting for the frame (until it is known the behaviour holds still: an idle decision in state
//    "waiting for camera mounting", no step()), then per accepted frame step(), the one
//    CommandOutput::send (cmd_vel, ~status, watchdog, ~enable, final stop), report(), a lazy
//    ~debug_image and lazy ~markers (in ~base_frame, with the frame's stamp).
//  * a behaviour's own diagnostics (addDiagnostics), updated before each frame's step().
//  * every callback runs guarded (an exception drops the message, never the node) and under
//    mutex(), the one the dynamic_reconfigure server shares.
template <typename ConfigT>
class BehaviourNodelet : public CheckedNodelet {
 public:
  using Config = ConfigT;

 protected:
  explicit BehaviourNodelet(BehaviourOptions options = {}) : options_(options) {}

  // Start-up only settings (targets, topics) before the first configure().
  // Throws std::invalid_argument naming a bad ~param.
  virtual void setup(ros::NodeHandle& /*nh*/, ros::NodeHandle& /*pnh*/, const Config& /*config*/) {}
  // Builds the cores from `config`, at start-up and for every live update; a new configuration
  // starts with fresh core state. Throws std::invalid_argument naming the first bad value.
  virtual void configure(const Config& config) = 0;
  // The behaviour's own topics and services, once output() exists.
  virtual void advertise(ros::NodeHandle& /*nh*/, ros::NodeHandle& /*pnh*/) {}
  // Usable intrinsics arrived in camera(); `changed`: the first ones or different from before.
  // By default the cores are rebuilt from the settings in force when they change.
  virtual void intrinsicsArrived(bool changed) {
    if (changed) configure(applied_config_);
  }
  // The camera's mounting in camera() differs from the one the cores were built with (the
  // ~params'). By default the cores are rebuilt from the settings in force.
  virtual void mountingChanged() { configure(applied_config_); }
  // One accepted frame: what the behaviour wants the robot to do.
  virtual Decision step(const Frame& frame) = 0;
  // After the frame's command went out (`sent`: what the robot was told, zero when quiet).
  virtual void report(const Frame& /*frame*/, const Twist2D& /*sent*/) {}
  // Draws the last step's findings on a copy of its frame (only while ~debug_image has a
  // subscriber).
  virtual void drawDebug(cv::Mat& /*canvas*/) {}
  // Adds what the last step believes, in the base frame (only while ~markers has a subscriber).
  virtual void addMarkers(RvizMarkers& /*markers*/) {}

  const CameraGeometry& camera() const { return camera_; }  // mounting and latest intrinsics
  bool hasIntrinsics() const { return intrinsics_ && intrinsics_->known(); }
  const std::string& cameraInfoTopic() const { return camera_info_topic_; }
  const std::string& imageTopic() const { return image_topic_; }
  CommandOutput& output() { return *output_; }
  boost::recursive_mutex& mutex() { return mutex_; }

  // Adds the status "<node>: <name>" to /diagnostics (next to CommandOutput's "<node>:
  // behaviour"): what `report()` says, asked under mutex() at most every ~diagnostic_period,
  // before each accepted frame's step() and on updateDiagnostics().
  void addDiagnostics(const std::string& name, const std::function<StatusReport()>& report) {
    if (!diagnostics_) {
      noteParamRead(getPrivateNodeHandle(), "diagnostic_period");  // read by the Updater
      diagnostics_ = std::make_unique<diagnostic_updater::Updater>(
          getNodeHandle(), getPrivateNodeHandle(), getPrivateNodeHandle().getNamespace());
      diagnostics_->setHardwareID("none");
    }
    diagnostics_->add(name, [report](diagnostic_updater::DiagnosticStatusWrapper& status) {
      const StatusReport health = report();
      status.summary(static_cast<unsigned char>(health.level), health.message);
      for (const auto& [key, value] : health.values) status.add(key, value);
    });
  }
  // Under mutex(): publishes the diagnostics when ~diagnostic_period has passed, or now (`force`).
  void updateDiagnostics(bool force = false) {
    if (!diagnostics_) return;
    if (force) {
      diagnostics_->force_update();
    } else {
      diagnostics_->update();
    }
  }

  // Subscribes `handle(const M&)` to `topic` (queue 1), guarded and under mutex() like the
  // camera callbacks. TCP_NODELAY: without it a small message (a camera_info sent just before
  // its frame) can wait ~40 ms for Nagle's algorithm and arrive after the frame.
  template <typename M, typename Handle>
  ros::Subscriber subscribe(ros::NodeHandle& nh, const std::string& topic, Handle handle) {
    const boost::function<void(const boost::shared_ptr<const M>&)> callback =
        [this, topic, handle](const boost::shared_ptr<const M>& msg) {
          guardedCallback(topic.c_str(), [&] {
            std::lock_guard<boost::recursive_mutex> lock(mutex_);
            handle(*msg);
          });
        };
    return nh.subscribe<M>(topic, 1, callback, ros::VoidConstPtr(),
                           ros::TransportHints().tcpNoDelay());
  }

 private:
  void init() final {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    std::lock_guard<boost::recursive_mutex> lock(mutex_);
    applied_config_ = readConfig<Config>(pnh);  // throws on bad ~params
    camera_ = readCameraMounting(pnh);
    mounting_ = std::make_unique<CameraMountingSource>(nh, pnh, camera_, getName());
    setup(nh, pnh, applied_config_);
    configure(applied_config_);
    output_ = std::make_unique<CommandOutput>(nh, pnh, options_.allow_reverse);
    if (options_.live_reconfigure) {
      reconfigure_ = std::make_unique<dynamic_reconfigure::Server<Unclamped<Config>>>(mutex_, pnh);
      reconfigure_->setCallback(
          [this](Unclamped<Config>& config, uint32_t) { reconfigure(config); });
    }
    advertise(nh, pnh);
    if (options_.debug_image) {
      debug_pub_ = image_transport::ImageTransport(pnh).advertise("debug_image", 1);
    }
    if (options_.markers)
      markers_pub_ = pnh.advertise<visualization_msgs::MarkerArray>("markers", 1);
    camera_info_sub_ = subscribe<sensor_msgs::CameraInfo>(
        nh, topics::kCameraInfo, [this](const sensor_msgs::CameraInfo& info) {
          bool usable = false;  // unless onCameraInfo gets to take it
          guardedCallback("camera_info", [&] { usable = onCameraInfo(info); });
          output_->cameraInfoHandled(usable);
        });
    camera_info_topic_ = camera_info_sub_.getTopic();
    intrinsics_ = std::make_unique<IntrinsicsSource>(
        param(pnh, "image_rectified", CameraDefaults::image_rectified), camera_info_topic_);
    // ~image_transport (e.g. compressed) read from this nodelet's private namespace, also when
    // it runs in a manager. The base name is resolved first so that a remapping of it also moves
    // the transport's topic (<base>/compressed): image_transport appends to the name as given.
    const image_transport::TransportHints hints("raw", ros::TransportHints(), pnh);
    noteParamRead(pnh, "image_transport");  // read by TransportHints
    image_sub_ = image_transport::ImageTransport(nh).subscribe(
        nh.resolveName(topics::kImage), 1, &BehaviourNodelet::onImage, this, hints);
    image_topic_ = image_sub_.getTopic();
  }

  // Called with mutex_ held by the dynamic_reconfigure server, with the values asked for: those
  // out of their .cfg range are clamped here, with a warning, rather than silently by the server.
  void reconfigure(Unclamped<Config>& asked) {
    for (const std::string& change : clampToRanges(asked)) {
      NODELET_WARN("reconfiguration: clamped %s", change.c_str());
    }
    Config& config = asked;
    const std::string error =
        applyOrKeep(config, applied_config_, [this](const Config& c) { configure(c); });
    if (!error.empty()) {
      NODELET_WARN("rejected reconfiguration, keeping the previous settings: %s", error.c_str());
    }
  }

  // Whether `info` was usable (taken as the intrinsics).
  bool onCameraInfo(const sensor_msgs::CameraInfo& info) {
    const IntrinsicsSource::Update update = intrinsics_->take(info, camera_);
    if (!update.error.empty()) {
      NODELET_ERROR_THROTTLE(5.0, "ignoring camera_info: %s", update.error.c_str());
      return false;
    }
    if (update.fitted) intrinsicsArrived(update.changed);
    return true;
  }

  // "" when camera_ holds intrinsics for frames of `size` (or no camera_info arrived yet), else
  // why the frame cannot be used.
  std::string intrinsicsFor(const cv::Size& size) {
    const IntrinsicsSource::Update update = intrinsics_->forFrame(size, camera_);
    if (!update.warning.empty()) NODELET_WARN_THROTTLE(5.0, "%s", update.warning.c_str());
    if (update.fitted) intrinsicsArrived(update.changed);
    return update.error;
  }

  // Every frame is counted once, under its outcome: one that throws is dropped as an error.
  void onImage(const sensor_msgs::ImageConstPtr& msg) {
    FrameOutcome outcome = FrameOutcome::kError;  // unless handleImage returns
    std::string error = "an unexpected error (logged)";
    guardedCallback("image", [&] { outcome = handleImage(msg, error); });
    output_->frameHandled(outcome, error);
  }

  FrameOutcome handleImage(const sensor_msgs::ImageConstPtr& msg, std::string& error) {
    std::lock_guard<boost::recursive_mutex> lock(mutex_);
    FrameCheck check;
    const cv_bridge::CvImageConstPtr image = bgrView(msg, check);
    error = check.error;
    if (image) {
      error = intrinsicsFor(image->image.size());
      if (!error.empty()) check.outcome = FrameOutcome::kSizeMismatch;
    }
    if (!error.empty()) {
      NODELET_ERROR_THROTTLE(1.0, "dropping frame: %s", error.c_str());
      return check.outcome;
    }
    // Only usable frames feed the watchdog: a stream of garbage must stop the robot too.
    output_->frameArrived();
    const Frame frame{msg->header, image->image, CommandOutput::frameTime(msg->header).toSec()};
    updateDiagnostics();
    const bool mounted = updateMounting(msg->header.frame_id);
    const Decision decision = mounted ? step(frame) : Decision{{}, false, kWaitingForMountingState};
    const Twist2D sent = output_->send(msg->header, decision.desired, decision.active,
                                       decision.state, decision.halt);
    report(frame, sent);
    if (options_.debug_image && debug_pub_.getNumSubscribers() > 0) {
      cv_bridge::CvImage debug(msg->header, "bgr8", image->image.clone());
      drawDebug(debug.image);
      debug_pub_.publish(debug.toImageMsg());
    }
    if (options_.markers && markers_pub_.getNumSubscribers() > 0) {
      std_msgs::Header header = msg->header;
      header.frame_id = mounting_->baseFrame();
      RvizMarkers markers(header);
      if (mounted) addMarkers(markers);  // else only the clearing: nothing was believed
      markers_pub_.publish(markers.message());
    }
    return FrameOutcome::kAccepted;
  }

  // The frame's mounting into camera_; false while it is unknown. A mounting the behaviour
  // rejects (configure() throws) is not taken: the previous one stays and it is tried again.
  bool updateMounting(const std::string& frame_id) {
    const CameraGeometry previous = camera_;
    bool changed = false;
    if (!mounting_->update(frame_id, camera_, changed)) return false;
    if (!changed) return true;
    try {
      mountingChanged();
    } catch (const std::invalid_argument& error) {
      NODELET_ERROR_THROTTLE(5.0, "keeping the previous camera mounting: %s", error.what());
      camera_ = previous;
      mountingChanged();
    }
    return true;
  }

  const BehaviourOptions options_;
  boost::recursive_mutex mutex_;  // the type dynamic_reconfigure::Server shares
  Config applied_config_;         // the settings in force, reported back after a rejected update
  CameraGeometry camera_;
  std::unique_ptr<CameraMountingSource> mounting_;
  std::unique_ptr<IntrinsicsSource> intrinsics_;
  std::string camera_info_topic_;
  std::string image_topic_;
  // Declared first among the ROS handles: destroyed last, it sends the final stop.
  std::unique_ptr<CommandOutput> output_;
  std::unique_ptr<dynamic_reconfigure::Server<Unclamped<Config>>> reconfigure_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;  // the behaviour's own, if any
  image_transport::Publisher debug_pub_;
  ros::Publisher markers_pub_;
  ros::Subscriber camera_info_sub_;
  image_transport::Subscriber image_sub_;
};

}  // namespace follow_bot_common
