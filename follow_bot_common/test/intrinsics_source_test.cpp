#include "follow_bot_common/ros/intrinsics_source.h"

#include <gtest/gtest.h>

#include <string>

#include <sensor_msgs/distortion_models.h>

namespace follow_bot_common {
namespace {

constexpr const char* kTopic = "/robot/camera/rgb/camera_info";

// A calibrated 640x480 camera: K and P with f = 500, 520 and the centre at (330, 250); the lens
// plumb_bob with `k1` (0: none).
sensor_msgs::CameraInfo info640(double k1 = 0.0) {
  sensor_msgs::CameraInfo info;
  info.width = 640;
  info.height = 480;
  info.distortion_model = sensor_msgs::distortion_models::PLUMB_BOB;
  info.D = {k1, 0.0, 0.0, 0.0, 0.0};
  info.K = {500, 0, 330, 0, 520, 250, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {500, 0, 330, 0, 0, 520, 250, 0, 0, 0, 1, 0};
  return info;
}

void expectIntrinsics(const CameraGeometry& camera, double scale) {
  EXPECT_DOUBLE_EQ(camera.fx, 500 * scale);
  EXPECT_DOUBLE_EQ(camera.fy, 520 * scale);
  EXPECT_DOUBLE_EQ(camera.cx, 330 * scale);
  EXPECT_DOUBLE_EQ(camera.cy, 250 * scale);
}

TEST(IntrinsicsSource, FramesBeforeAnyCameraInfoUseTheDefaults) {
  IntrinsicsSource source(false, kTopic);
  CameraGeometry camera;
  const CameraGeometry defaults = camera;
  const IntrinsicsSource::Update update = source.forFrame({1280, 720}, camera);
  EXPECT_EQ(update.error, "");
  EXPECT_FALSE(update.fitted);
  EXPECT_FALSE(source.known());
  EXPECT_TRUE(sameIntrinsics(camera, defaults));
}

TEST(IntrinsicsSource, TakesACameraInfoAtOnceAndTheSameOneChangesNothing) {
  IntrinsicsSource source(false, kTopic);
  CameraGeometry camera;
  camera.height_m = 0.42;  // the mounting is not camera_info's
  IntrinsicsSource::Update update = source.take(info640(), camera);
  EXPECT_EQ(update.error, "");
  EXPECT_TRUE(update.fitted);
  EXPECT_TRUE(update.changed);
  EXPECT_TRUE(source.known());
  expectIntrinsics(camera, 1.0);
  EXPECT_FALSE(camera.lens);  // no distortion: a pinhole
  EXPECT_EQ(camera.height_m, 0.42);

  update = source.forFrame({640, 480}, camera);
  EXPECT_EQ(update.error, "");
  EXPECT_FALSE(update.fitted);
  update = source.take(info640(), camera);
  EXPECT_TRUE(update.fitted);
  EXPECT_FALSE(update.changed);
}

TEST(IntrinsicsSource, ScalesTheIntrinsicsToAFrameThatIsTheImageResized) {
  IntrinsicsSource source(false, kTopic);
  CameraGeometry camera;
  source.take(info640(-0.2), camera);
  ASSERT_TRUE(camera.lens);
  EXPECT_DOUBLE_EQ(camera.lens->camera_matrix(0, 0), 500);

  const IntrinsicsSource::Update update = source.forFrame({320, 240}, camera);
  EXPECT_EQ(update.error, "");
  EXPECT_TRUE(update.fitted);
  EXPECT_TRUE(update.changed);
  expectIntrinsics(camera, 0.5);
  EXPECT_DOUBLE_EQ(camera.lens->camera_matrix(0, 0), 250);
  EXPECT_DOUBLE_EQ(camera.lens->camera_matrix(1, 2), 125);
  EXPECT_DOUBLE_EQ(camera.lens->distortion[0], -0.2);
}

TEST(IntrinsicsSource, KeepsTheIntrinsicsInForceWhenACameraInfoDescribesOtherFrames) {
  IntrinsicsSource source(false, kTopic);
  CameraGeometry camera;
  source.take(info640(), camera);
  source.forFrame({640, 480}, camera);
  sensor_msgs::CameraInfo wide = info640();
  wide.width = 1280;
  wide.height = 720;
  IntrinsicsSource::Update update = source.take(wide, camera);
  EXPECT_EQ(update.error, "");  // usable: it may be for the frames to come
  EXPECT_FALSE(update.fitted);

  update = source.forFrame({640, 480}, camera);
  EXPECT_EQ(update.error, "");
  EXPECT_EQ(update.warning, std::string(kTopic) +
                                " is for 1280x720, not frames of 640x480: keeping the intrinsics "
                                "of the last one that was");
  expectIntrinsics(camera, 1.0);

  // Frames of its size come: it is taken.
  update = source.forFrame({1280, 720}, camera);
  EXPECT_EQ(update.error, "");
  EXPECT_TRUE(update.fitted);
  EXPECT_EQ(update.warning, "");
}

TEST(IntrinsicsSource, AFrameNoCameraInfoDescribesCannotBeUsed) {
  IntrinsicsSource source(false, kTopic);
  CameraGeometry camera;
  sensor_msgs::CameraInfo wide = info640();
  wide.width = 1280;
  wide.height = 720;
  source.take(wide, camera);
  const IntrinsicsSource::Update update = source.forFrame({640, 480}, camera);
  EXPECT_EQ(update.error, "the frame is 640x480 but " + std::string(kTopic) +
                              " is for 1280x720, not an image of that shape");
}

TEST(IntrinsicsSource, IgnoresABrokenCameraInfoAndKeepsTheCamera) {
  IntrinsicsSource source(false, kTopic);
  CameraGeometry camera;
  source.take(info640(), camera);
  const CameraGeometry before = camera;

  sensor_msgs::CameraInfo half_size = info640();
  half_size.width = 0;
  EXPECT_EQ(source.take(half_size, camera).error,
            "its size 0x480 is no frame's (1-16384 each, or both 0)");

  sensor_msgs::CameraInfo fisheye = info640(0.1);
  fisheye.distortion_model = "equidistant";
  EXPECT_EQ(source.take(fisheye, camera).error,
            "distortion_model 'equidistant' is not supported (plumb_bob, rational_polynomial), "
            "or send rectified frames");

  sensor_msgs::CameraInfo short_d = info640(0.1);
  short_d.D.resize(4);
  EXPECT_EQ(source.take(short_d, camera).error,
            "D of a plumb_bob lens must have 5 coefficients, got 4");
  EXPECT_TRUE(sameIntrinsics(camera, before));
}

TEST(IntrinsicsSource, RectifiedFramesTakeTheProjectionWithoutTheLens) {
  IntrinsicsSource source(true, kTopic);
  CameraGeometry camera;
  sensor_msgs::CameraInfo fisheye = info640(0.1);
  fisheye.distortion_model = "equidistant";
  fisheye.P[0] = 480;  // rectified: P differs from K
  EXPECT_EQ(source.take(fisheye, camera).error, "");
  EXPECT_DOUBLE_EQ(camera.fx, 480);
  EXPECT_FALSE(camera.lens);
}

}  // namespace
}  // namespace follow_bot_common
