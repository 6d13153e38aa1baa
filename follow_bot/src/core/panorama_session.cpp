#include "follow_bot/panorama_session.h"

#include <cmath>
#include <exception>
#include <utility>

namespace follow_bot {

PanoramaSession::PanoramaSession(const PanoramaSessionConfig& config)
    : config_(config), capture_(config.capture) {}

void PanoramaSession::request(double now) {
  pending_ = true;
  started_ = false;
  requested_at_ = now;
}

bool PanoramaSession::orientation(double x, double y, double z, double w) {
  const double yaw = yawOfQuaternion(x, y, z, w);
  if (!std::isfinite(yaw)) return false;
  yaw_ = yaw;
  return true;
}

double PanoramaSession::update(const cv::Mat& frame, double wall) {
  last_frame_wall_ = wall;
  stitch_due_ = false;
  if (!yaw_) return 0.0;
  if (pending_ && !started_) {
    started_ = true;
    capture_.start(*yaw_);
    frames_.clear();
    yaws_.clear();
  }
  if (!capture_.active()) return 0.0;
  const PanoramaCapture::Step step = capture_.update(*yaw_);
  if (step.grab) {
    frames_.push_back(frame.clone());
    yaws_.push_back(*yaw_);
  }
  stitch_due_ = step.finished;
  return step.angular;
}

CaptureStitch PanoramaSession::stitch(const CameraGeometry& camera) {
  stitch_due_ = false;
  CaptureStitch stitched;
  try {  // the caller must get an answer whatever the stitcher does
    stitched = stitchCapture(frames_, yaws_, camera, config_.match, config_.method);
  } catch (const std::exception& error) {
    stitched = {cv::Mat(), std::string("stitching failed: ") + error.what()};
  }
  end({stitched.ok(), stitched.message});
  return stitched;
}

bool PanoramaSession::abortIfStalled(double wall, double now, bool shutting_down) {
  if (!pending_) return false;
  const bool timed_out = now - requested_at_ > config_.capture_timeout;
  if (framesArriving(wall) && !timed_out && !shutting_down) return false;
  capture_.abort();
  ++aborts_;
  end({false, timed_out ? "capture took longer than ~capture_timeout"
                        : "camera frames stopped during the capture"});
  return true;
}

StatusReport PanoramaSession::report() const {
  StatusReport report;
  if (last_ && !last_->success) {
    report.level = StatusReport::Level::kError;
    report.message = "last capture failed: " + last_->message;
  } else {
    report.message = "running";
  }
  report.values = {{"state", busy() ? "capturing" : "idle"},
                   {"captures stopped for lost frames or time", std::to_string(aborts_)},
                   {"last capture", last_ ? last_->message : "none"}};
  return report;
}

void PanoramaSession::end(Outcome outcome) {
  pending_ = false;
  started_ = false;
  last_ = std::move(outcome);
}

}  // namespace follow_bot
