#include "follow_bot_common/ros/camera_mounting_source.h"

#include <map>
#include <mutex>
#include <stdexcept>
#include <utility>

#include <ros/console.h>
#include <tf2/exceptions.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "follow_bot_common/CameraDefaults.h"
#include "follow_bot_common/camera_mounting.h"
#include "follow_bot_common/ros/params.h"

namespace follow_bot_common {

struct SharedTfListener {
  explicit SharedTfListener(const ros::NodeHandle& nh) : listener(buffer, nh) {}
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener;
};

namespace {

// One tf2 buffer and listener per process for each pair of tf topics as `nh` resolves them: the
// behaviours in one nodelet manager share one /tf subscription and cache, and a robot whose /tf
// is remapped to its own (tests/closed_loop/test_two_robots.py) keeps its own. Made on first use,
// gone with its last user.
std::shared_ptr<SharedTfListener> sharedTfListener(const ros::NodeHandle& nh) {
  static std::mutex mutex;
  static std::map<std::pair<std::string, std::string>, std::weak_ptr<SharedTfListener>> listeners;
  const std::pair<std::string, std::string> topics(nh.resolveName("/tf"),
                                                   nh.resolveName("/tf_static"));
  std::lock_guard<std::mutex> lock(mutex);
  std::shared_ptr<SharedTfListener> listener = listeners[topics].lock();
  if (!listener) {
    listener = std::make_shared<SharedTfListener>(nh);
    listeners[topics] = listener;
  }
  return listener;
}

}  // namespace

CameraMountingSource::CameraMountingSource(ros::NodeHandle& nh, const ros::NodeHandle& pnh,
                                           CameraGeometry fallback, std::string name)
    : name_(std::move(name)), fallback_(std::move(fallback)) {
  const std::string source =
      param<std::string>(pnh, "camera_mounting", CameraDefaults::camera_mounting);
  if (source != "tf" && source != "params") {
    throw std::invalid_argument("~camera_mounting must be 'tf' or 'params', got '" + source + "'");
  }
  use_tf_ = source == "tf";
  base_frame_ = param<std::string>(pnh, "base_frame", CameraDefaults::base_frame);
  if (base_frame_.empty()) throw std::invalid_argument("~base_frame must not be empty");
  timeout_s_ = positiveParam(pnh, "mounting_timeout", CameraDefaults::mounting_timeout);
  if (use_tf_) tf_ = sharedTfListener(nh);
}

bool CameraMountingSource::update(const std::string& frame_id, CameraGeometry& camera,
                                  bool& changed) {
  changed = false;
  if (!use_tf_) {
    if (!known_) use(fallback_, "~params (~camera_mounting params)", camera, changed);
    return true;
  }
  std::string why;
  if (const auto mounting = fromTf(frame_id, camera, why)) {
    use(*mounting, "tf (" + base_frame_ + " <- " + frame_id + ")", camera, changed);
    from_tf_ = true;
    return true;
  }
  if (from_tf_) {  // known from tf before: keep it, the description may be restarting
    ROS_WARN_THROTTLE(5.0, "%s: keeping the last camera mounting from tf: %s", name_.c_str(),
                      why.c_str());
    return true;
  }
  if (known_) return true;  // fell back to the ~params; tf still replaces them when it comes
  const auto now = std::chrono::steady_clock::now();
  if (!waiting_since_) waiting_since_ = now;
  if (std::chrono::duration<double>(now - *waiting_since_).count() < timeout_s_) {
    ROS_WARN_THROTTLE(2.0,
                      "%s: waiting for the camera mounting: no transform %s <- '%s' in tf yet "
                      "(%s); holding still; the mounting ~params are used after "
                      "~mounting_timeout %g s",
                      name_.c_str(), base_frame_.c_str(), frame_id.c_str(), why.c_str(),
                      timeout_s_);
    return false;
  }
  ROS_WARN(
      "%s: no camera mounting from tf (%s <- '%s') within ~mounting_timeout %g s: falling "
      "back to the mounting ~params: %s",
      name_.c_str(), base_frame_.c_str(), frame_id.c_str(), timeout_s_,
      describeMounting(fallback_).c_str());
  use(fallback_, "~params (tf fallback)", camera, changed);
  return true;
}

std::optional<CameraGeometry> CameraMountingSource::fromTf(const std::string& frame_id,
                                                           const CameraGeometry& camera,
                                                           std::string& why) {
  if (frame_id.empty()) {
    why = "the image has no header.frame_id";
    return std::nullopt;
  }
  geometry_msgs::TransformStamped camera_in_base, base_on_floor;
  try {
    camera_in_base = tf_->buffer.lookupTransform(base_frame_, frame_id, ros::Time(0));
  } catch (const tf2::TransformException& error) {
    why = error.what();
    return std::nullopt;
  }
  double base_height = 0.0;
  if (base_frame_ != kFootprintFrame && tf_->buffer._frameExists(kFootprintFrame)) {
    try {
      base_height = tf_->buffer.lookupTransform(kFootprintFrame, base_frame_, ros::Time(0))
                        .transform.translation.z;
    } catch (const tf2::TransformException& error) {
      why = error.what();
      return std::nullopt;
    }
  }
  const auto& t = camera_in_base.transform.translation;
  const auto& q = camera_in_base.transform.rotation;
  const cv::Matx33d rotation = rotationOfQuaternion(cv::Vec4d(q.x, q.y, q.z, q.w));
  CameraGeometry mounted = camera;
  std::string warning;
  const std::string error =
      mountingFromTransform(cv::Vec3d(t.x, t.y, t.z), rotation, base_height, mounted, warning);
  if (!error.empty()) {
    ROS_ERROR_THROTTLE(5.0, "%s: cannot use the camera mounting from tf (%s <- '%s'): %s",
                       name_.c_str(), base_frame_.c_str(), frame_id.c_str(), error.c_str());
    why = error;
    return std::nullopt;
  }
  if (!warning.empty()) ROS_WARN_ONCE("%s: camera mounting: %s", name_.c_str(), warning.c_str());
  return mounted;
}

void CameraMountingSource::use(const CameraGeometry& mounting, const std::string& source,
                               CameraGeometry& camera, bool& changed) {
  // `camera` is what the cores were built with: the same mounting needs no rebuild (for some
  // cores, e.g. the sign parker's, an expensive one), but is logged once as the one in use.
  changed = !sameMounting(mounting, camera);
  const bool first = !known_;
  camera.height_m = mounting.height_m;
  camera.pitch_rad = mounting.pitch_rad;
  camera.x_offset_m = mounting.x_offset_m;
  known_ = true;
  if (changed || first) {
    ROS_INFO("%s: camera mounting from %s: %s", name_.c_str(), source.c_str(),
             describeMounting(camera).c_str());
  }
}

}  // namespace follow_bot_common
