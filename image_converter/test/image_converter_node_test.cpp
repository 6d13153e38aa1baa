// rostest: drives a running ImageConverter (node or nodelet) through its topics.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>

#include <opencv2/imgproc.hpp>

#include <cstring>
#include <string>
#include <vector>

namespace {

constexpr char kInput[] = "/camera/rgb/image_raw";
constexpr char kOutput[] = "/image_converter/output";

class ImageConverterNode : public ::testing::Test {
 protected:
  void SetUp() override {
    publisher_ = nh_.advertise<sensor_msgs::Image>(kInput, 10);
    subscriber_ = nh_.subscribe(kOutput, 10, &ImageConverterNode::onOutput, this);
    // The converter subscribes its input only once somebody listens to its output.
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(20.0);
    while ((publisher_.getNumSubscribers() == 0 || subscriber_.getNumPublishers() == 0) &&
           ros::WallTime::now() < deadline) {
      ros::spinOnce();
      ros::WallDuration(0.01).sleep();
    }
    ASSERT_GT(publisher_.getNumSubscribers(), 0u) << "converter never subscribed to " << kInput;
  }

  void onOutput(const sensor_msgs::ImageConstPtr& msg) { received_.push_back(msg); }

  // Publishes `msg` and waits up to `timeout` for one output; returns null when none came.
  sensor_msgs::ImageConstPtr roundTrip(const sensor_msgs::Image& msg, double timeout = 5.0) {
    received_.clear();
    publisher_.publish(msg);
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
    while (received_.empty() && ros::WallTime::now() < deadline) {
      ros::spinOnce();
      ros::WallDuration(0.005).sleep();
    }
    return received_.empty() ? nullptr : received_.front();
  }

  ros::NodeHandle nh_;
  ros::Publisher publisher_;
  ros::Subscriber subscriber_;
  std::vector<sensor_msgs::ImageConstPtr> received_;
};

sensor_msgs::Image messageOf(const cv::Mat& image, const std::string& encoding, uint32_t seq) {
  sensor_msgs::Image msg;
  msg.header.seq = seq;
  msg.header.stamp = ros::Time(100, seq);
  msg.header.frame_id = "camera_rgb_optical_frame";
  msg.width = image.cols;
  msg.height = image.rows;
  msg.encoding = encoding;
  msg.step = image.cols * image.elemSize();
  msg.data.resize(msg.step * image.rows);
  for (int r = 0; r < image.rows; ++r) {
    std::memcpy(&msg.data[r * msg.step], image.ptr(r), msg.step);
  }
  return msg;
}

// A deterministic colourful test pattern, so that a swapped channel or a shifted row shows.
cv::Mat pattern(int rows, int cols) {
  cv::Mat bgr(rows, cols, CV_8UC3);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      bgr.at<cv::Vec3b>(r, c) = cv::Vec3b(c * 7 % 256, r * 5 % 256, (r + c) * 3 % 256);
    }
  }
  return bgr;
}

// What the converter must publish for a BGR8 frame: the lecture's circle, drawn independently.
cv::Mat expectedOutput(const cv::Mat& bgr) {
  cv::Mat expected = bgr.clone();
  cv::circle(expected, cv::Point(bgr.cols / 2, bgr.rows / 2), 25, cv::Scalar(0, 0, 255), 2,
             cv::LINE_8);
  return expected;
}

void expectImageEquals(const sensor_msgs::Image& msg, const cv::Mat& expected) {
  ASSERT_EQ(msg.encoding, "bgr8");
  ASSERT_EQ(static_cast<int>(msg.width), expected.cols);
  ASSERT_EQ(static_cast<int>(msg.height), expected.rows);
  ASSERT_EQ(msg.data.size(), msg.step * msg.height);
  int mismatches = 0;
  for (int r = 0; r < expected.rows; ++r) {
    for (int c = 0; c < expected.cols; ++c) {
      const uint8_t* got = &msg.data[r * msg.step + c * 3];
      const cv::Vec3b& want = expected.at<cv::Vec3b>(r, c);
      if (got[0] != want[0] || got[1] != want[1] || got[2] != want[2]) ++mismatches;
    }
  }
  EXPECT_EQ(mismatches, 0);
}

TEST_F(ImageConverterNode, AnnotatesEverySupportedEncodingPixelByPixel) {
  const cv::Mat bgr = pattern(120, 160);
  cv::Mat rgb, bgra, rgba, mono8, mono16;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  cv::cvtColor(bgr, bgra, cv::COLOR_BGR2BGRA);
  cv::cvtColor(bgr, rgba, cv::COLOR_BGR2RGBA);
  cv::cvtColor(bgr, mono8, cv::COLOR_BGR2GRAY);
  mono8.convertTo(mono16, CV_16U, 256.0);
  cv::Mat grey_bgr;
  cv::cvtColor(mono8, grey_bgr, cv::COLOR_GRAY2BGR);

  struct Case {
    std::string encoding;
    cv::Mat input;
    cv::Mat as_bgr;
  };
  const std::vector<Case> cases = {
      {"bgr8", bgr, bgr},   {"rgb8", rgb, bgr},         {"bgra8", bgra, bgr},
      {"rgba8", rgba, bgr}, {"mono8", mono8, grey_bgr}, {"mono16", mono16, grey_bgr},
      {"8UC3", bgr, bgr},   {"8UC1", mono8, grey_bgr},
  };
  uint32_t seq = 1;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.encoding);
    const sensor_msgs::Image msg = messageOf(c.input, c.encoding, seq++);
    const sensor_msgs::ImageConstPtr out = roundTrip(msg);
    ASSERT_TRUE(out) << "no output for " << c.encoding;
    EXPECT_EQ(out->header.stamp, msg.header.stamp);
    EXPECT_EQ(out->header.frame_id, msg.header.frame_id);
    expectImageEquals(*out, expectedOutput(c.as_bgr));
  }
}

TEST_F(ImageConverterNode, SurvivesMalformedFramesAndProcessesTheNextGoodOne) {
  const cv::Mat bgr = pattern(96, 128);
  const sensor_msgs::Image good = messageOf(bgr, "bgr8", 1);
  std::vector<std::pair<std::string, sensor_msgs::Image>> bad;
  auto add = [&](const std::string& name, auto mutate) {
    sensor_msgs::Image msg = good;
    mutate(msg);
    bad.emplace_back(name, msg);
  };
  add("zero width", [](sensor_msgs::Image& m) { m.width = 0; });
  add("zero height", [](sensor_msgs::Image& m) { m.height = 0; });
  add("short step", [](sensor_msgs::Image& m) { m.step = m.width * 3 - 1; });
  add("truncated data", [](sensor_msgs::Image& m) { m.data.resize(m.data.size() / 2); });
  add("empty data", [](sensor_msgs::Image& m) { m.data.clear(); });
  add("absurd size", [](sensor_msgs::Image& m) {
    m.width = 1u << 30;
    m.height = 1u << 30;
    m.step = 3u << 30;
  });
  add("height overflow", [](sensor_msgs::Image& m) { m.height = 0xFFFFFFFFu; });
  add("bayer", [](sensor_msgs::Image& m) { m.encoding = "bayer_rggb8"; });
  add("32FC1", [](sensor_msgs::Image& m) { m.encoding = "32FC1"; });
  add("yuv422", [](sensor_msgs::Image& m) { m.encoding = "yuv422"; });
  add("empty encoding", [](sensor_msgs::Image& m) { m.encoding.clear(); });

  for (const auto& [name, msg] : bad) {
    SCOPED_TRACE(name);
    EXPECT_FALSE(roundTrip(msg, 0.3)) << "a malformed frame produced output: " << name;
    const sensor_msgs::ImageConstPtr out = roundTrip(good);
    ASSERT_TRUE(out) << "converter stopped answering after: " << name;
    expectImageEquals(*out, expectedOutput(bgr));
  }
}

TEST_F(ImageConverterNode, LeavesSmallImagesUnannotated) {
  const cv::Mat small = pattern(40, 40);
  const sensor_msgs::ImageConstPtr out = roundTrip(messageOf(small, "bgr8", 7));
  ASSERT_TRUE(out);
  expectImageEquals(*out, small);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "image_converter_node_test");
  ros::NodeHandle nh;  // keeps the node alive for the whole run
  return RUN_ALL_TESTS();
}
