#include "follow_bot/panorama_session.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace follow_bot {
namespace {

constexpr double kPi = 3.141592653589793;

// The quaternion of a rotation by `yaw` about z.
bool turnTo(PanoramaSession& session, double yaw) {
  return session.orientation(0.0, 0.0, std::sin(yaw / 2.0), std::cos(yaw / 2.0));
}

PanoramaSessionConfig shortSweep() {
  PanoramaSessionConfig config;
  config.capture.total_angle = 40.0 * kPi / 180.0;  // three headings, 20 deg apart
  config.capture.settle_frames = 0;
  config.method = StitchMethod::kRotation;
  return config;
}

TEST(PanoramaSession, TakesOnlyUnitQuaternionsAsThePose) {
  PanoramaSession session;
  EXPECT_FALSE(session.hasPose());
  EXPECT_FALSE(session.orientation(0.0, 0.0, 0.0, 0.5));
  EXPECT_FALSE(session.hasPose());
  EXPECT_TRUE(turnTo(session, 0.3));
  EXPECT_TRUE(session.hasPose());
}

// Requests a capture at yaw 0 and feeds `frame` at 30 frames per second, the robot turning as
// told, until the stitch is due.
void turnThroughCapture(PanoramaSession& session, const cv::Mat& frame) {
  ASSERT_TRUE(turnTo(session, 0.0));
  session.request(0.0);
  EXPECT_TRUE(session.busy());
  double yaw = 0.0;
  double wall = 0.0;
  for (int frames = 0; frames < 10000 && !session.stitchDue(); ++frames) {
    wall += 1.0 / 30.0;
    yaw += session.update(frame, wall) / 30.0;
    EXPECT_TRUE(session.turning() || session.stitchDue());
    ASSERT_TRUE(turnTo(session, yaw));
  }
  ASSERT_TRUE(session.stitchDue());
  EXPECT_NEAR(yaw, 0.0, 0.5 * kPi / 180.0);  // back at the start, within yaw_tolerance
  EXPECT_FALSE(session.turning());
  EXPECT_TRUE(session.busy());  // until the stitch says how it ended
}

TEST(PanoramaSession, ARequestedCaptureTurnsGrabsAndEndsWithTheStitch) {
  PanoramaSession session(shortSweep());
  cv::Mat frame(48, 64, CV_8UC3);
  cv::RNG(7).fill(frame, cv::RNG::UNIFORM, 0, 256);
  EXPECT_EQ(session.update(frame, 0.0), 0.0);  // no pose, no request: still
  EXPECT_FALSE(session.busy());
  turnThroughCapture(session, frame);
  const CaptureStitch stitched = session.stitch(CameraGeometry());
  ASSERT_TRUE(stitched.ok()) << stitched.message;
  EXPECT_FALSE(session.busy());
  EXPECT_FALSE(session.stitchDue());
  ASSERT_TRUE(session.last());
  EXPECT_TRUE(session.last()->success);
  EXPECT_EQ(session.last()->message, stitched.message);
  const StatusReport report = session.report();
  EXPECT_EQ(report.level, StatusReport::Level::kOk);
  EXPECT_EQ(report.message, "running");
  using Value = std::pair<std::string, std::string>;
  EXPECT_EQ(report.values, (std::vector<Value>{{"state", "idle"},
                                               {"captures stopped for lost frames or time", "0"},
                                               {"last capture", stitched.message}}));
}

TEST(PanoramaSession, AFailedStitchEndsTheCaptureWithItsReason) {
  PanoramaSession session(shortSweep());
  turnThroughCapture(session, cv::Mat(48, 64, CV_8UC3, cv::Scalar(40, 90, 160)));
  EXPECT_FALSE(session.stitch(CameraGeometry()).ok());
  EXPECT_FALSE(session.busy());
  EXPECT_EQ(session.aborts(), 0);
  const StatusReport report = session.report();
  EXPECT_EQ(report.level, StatusReport::Level::kError);
  EXPECT_EQ(report.message,
            "last capture failed: stitching failed: image 1 is blank (grey-level standard "
            "deviation 0.000000)");
}

TEST(PanoramaSession, FramesStoppingForTheFrameTimeoutAbortTheCapture) {
  PanoramaSession session(shortSweep());  // frame_timeout 1 s
  const cv::Mat frame(48, 64, CV_8UC3, cv::Scalar(0, 0, 0));
  ASSERT_TRUE(turnTo(session, 0.0));
  session.update(frame, 10.0);
  EXPECT_TRUE(session.framesArriving(11.0));
  EXPECT_FALSE(session.framesArriving(11.01));
  session.request(5.0);
  EXPECT_GT(session.update(frame, 10.5), 0.0);  // turning left toward the sweep's left end
  EXPECT_FALSE(session.abortIfStalled(11.5, 6.0, false));
  EXPECT_TRUE(session.busy());
  EXPECT_TRUE(session.abortIfStalled(11.51, 6.0, false));
  EXPECT_FALSE(session.busy());
  EXPECT_FALSE(session.turning());
  EXPECT_FALSE(session.abortIfStalled(20.0, 6.0, false));  // nothing left to abort
  EXPECT_EQ(session.aborts(), 1);
  EXPECT_FALSE(session.last()->success);
  const StatusReport report = session.report();
  EXPECT_EQ(report.level, StatusReport::Level::kError);
  EXPECT_EQ(report.message, "last capture failed: camera frames stopped during the capture");
  EXPECT_EQ(report.values[1],
            (std::pair<std::string, std::string>{"captures stopped for lost frames or time", "1"}));
}

TEST(PanoramaSession, ACaptureLongerThanTheCaptureTimeoutIsAborted) {
  PanoramaSessionConfig config = shortSweep();
  config.capture_timeout = 2.0;
  PanoramaSession session(config);
  const cv::Mat frame(48, 64, CV_8UC3, cv::Scalar(0, 0, 0));
  ASSERT_TRUE(turnTo(session, 0.0));
  session.request(100.0);
  session.update(frame, 0.0);
  EXPECT_FALSE(session.abortIfStalled(0.5, 102.0, false));
  EXPECT_TRUE(session.abortIfStalled(0.5, 102.01, false));
  EXPECT_EQ(session.last()->message, "capture took longer than ~capture_timeout");
}

TEST(PanoramaSession, ShuttingDownAbortsAsLostFrames) {
  PanoramaSession session(shortSweep());
  ASSERT_TRUE(turnTo(session, 0.0));
  session.update(cv::Mat(48, 64, CV_8UC3, cv::Scalar(0, 0, 0)), 10.0);
  session.request(0.0);
  EXPECT_TRUE(session.abortIfStalled(10.1, 0.0, true));
  EXPECT_EQ(session.last()->message, "camera frames stopped during the capture");
}

}  // namespace
}  // namespace follow_bot
