// image_transport publisher -> `compressed` plugins -> subscriber with _image_transport
// compressed: exact pixels for PNG, JPEG quality 80 within a few grey levels, the format strings
// on the wire, and malformed CompressedImages dropped without a callback or a crash.
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <image_transport/image_transport.h>
#include <ros/ros.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>

#include <opencv2/core.hpp>

namespace {

sensor_msgs::ImagePtr rampImage(uint32_t seq) {
  auto image = boost::make_shared<sensor_msgs::Image>();
  image->header.seq = seq;
  image->header.frame_id = "camera_rgb_optical_frame";
  image->height = 48;
  image->width = 64;
  image->encoding = "bgr8";
  image->step = image->width * 3;
  image->data.resize(image->step * image->height);
  for (uint32_t r = 0; r < image->height; ++r) {
    for (uint32_t c = 0; c < image->width; ++c) {
      uint8_t* pixel = &image->data[r * image->step + 3 * c];
      pixel[0] = static_cast<uint8_t>(2 * c);
      pixel[1] = static_cast<uint8_t>(4 * r);
      pixel[2] = static_cast<uint8_t>(100 + c / 2);
    }
  }
  return image;
}

class Received {
 public:
  void onImage(const sensor_msgs::ImageConstPtr& image) {
    std::lock_guard<std::mutex> lock(mutex_);
    images_.push_back(image);
  }
  void onCompressed(const sensor_msgs::CompressedImageConstPtr& message) {
    std::lock_guard<std::mutex> lock(mutex_);
    formats_.push_back(message->format);
  }
  size_t count() {
    std::lock_guard<std::mutex> lock(mutex_);
    return images_.size();
  }
  sensor_msgs::ImageConstPtr last() {
    std::lock_guard<std::mutex> lock(mutex_);
    return images_.back();
  }
  std::string lastFormat() {
    std::lock_guard<std::mutex> lock(mutex_);
    return formats_.empty() ? "" : formats_.back();
  }

 private:
  std::mutex mutex_;
  std::vector<sensor_msgs::ImageConstPtr> images_;
  std::vector<std::string> formats_;
};

// Publishes `image` until `received` grows past `before` (up to 10 s).
bool deliver(const image_transport::Publisher& publisher, const sensor_msgs::ImagePtr& image,
             Received& received, size_t before) {
  for (int i = 0; i < 200 && received.count() <= before; ++i) {
    publisher.publish(image);
    ros::Duration(0.05).sleep();
  }
  return received.count() > before;
}

double maxDifference(const sensor_msgs::Image& a, const sensor_msgs::Image& b) {
  const cv::Mat ma(a.height, a.width, CV_8UC3, const_cast<uint8_t*>(a.data.data()), a.step);
  const cv::Mat mb(b.height, b.width, CV_8UC3, const_cast<uint8_t*>(b.data.data()), b.step);
  return cv::norm(ma, mb, cv::NORM_INF);
}

struct Link {
  Link(image_transport::ImageTransport& transport, ros::NodeHandle& nh, const std::string& topic)
      : publisher(transport.advertise(topic, 1)),
        subscriber(transport.subscribe(topic, 10, &Received::onImage, &received,
                                       image_transport::TransportHints("compressed"))),
        wire(nh.subscribe(topic + "/compressed", 10, &Received::onCompressed, &received)) {}
  Received received;
  image_transport::Publisher publisher;
  image_transport::Subscriber subscriber;
  ros::Subscriber wire;
};

// `sent` published on `topic` (its ~params pick the format) and received through the
// compressed transport, expected as bgr8 with the wire format string `format`: the image that
// came back, null when none came within 10 s.
sensor_msgs::ImageConstPtr roundTrip(const std::string& topic, const sensor_msgs::ImagePtr& sent,
                                     const std::string& format) {
  ros::NodeHandle nh;
  image_transport::ImageTransport transport(nh);
  Link link(transport, nh, topic);
  if (!deliver(link.publisher, sent, link.received, 0)) return nullptr;
  sensor_msgs::ImageConstPtr got = link.received.last();
  EXPECT_EQ(got->encoding, "bgr8");
  EXPECT_EQ(link.received.lastFormat(), format);
  return got;
}

TEST(CompressedRoundTrip, PngIsExact) {
  const auto sent = rampImage(1);
  const auto got = roundTrip("png_out", sent, "bgr8; png compressed bgr8");
  ASSERT_TRUE(got);
  EXPECT_EQ(got->header.frame_id, "camera_rgb_optical_frame");
  EXPECT_EQ(got->width, 64u);
  EXPECT_EQ(got->height, 48u);
  EXPECT_EQ(maxDifference(*got, *sent), 0.0);
}

TEST(CompressedRoundTrip, JpegQuality80IsClose) {
  const auto sent = rampImage(2);
  const auto got = roundTrip("jpeg_out", sent, "bgr8; jpeg compressed bgr8");
  ASSERT_TRUE(got);
  EXPECT_GT(maxDifference(*got, *sent), 0.0);  // lossy: proves it went through JPEG
  EXPECT_LE(maxDifference(*got, *sent), 12.0);
}

TEST(CompressedRoundTrip, MalformedPayloadsAreDropped) {
  ros::NodeHandle nh;
  image_transport::ImageTransport transport(nh);
  Received received;
  const auto subscriber = transport.subscribe("fuzzed", 10, &Received::onImage, &received,
                                              image_transport::TransportHints("compressed"));
  const auto raw = nh.advertise<sensor_msgs::CompressedImage>("fuzzed/compressed", 10);
  for (int i = 0; i < 100 && raw.getNumSubscribers() == 0; ++i) ros::Duration(0.05).sleep();
  ASSERT_GT(raw.getNumSubscribers(), 0u);
  sensor_msgs::CompressedImage bad;
  bad.format = "bgr8; jpeg compressed bgr8";
  for (const std::vector<uint8_t>& payload :
       {std::vector<uint8_t>{}, std::vector<uint8_t>{0xff, 0xd8, 0xff, 0xe0, 0x00},
        std::vector<uint8_t>(4096, 0x42)}) {
    bad.data = payload;
    raw.publish(bad);
  }
  bad.format = "yuv422; png compressed bgr8";
  raw.publish(bad);
  ros::Duration(1.0).sleep();
  EXPECT_EQ(received.count(), 0u);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "compressed_round_trip");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
