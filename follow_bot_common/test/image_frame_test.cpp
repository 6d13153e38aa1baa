#include "follow_bot_common/image_frame.h"
#include "follow_bot_common/frame_counts.h"

#include <gtest/gtest.h>

#include <vector>

namespace follow_bot_common {
namespace {

RawFrame frameOf(const std::vector<std::uint8_t>& data, std::uint32_t width, std::uint32_t height,
                 std::uint32_t step, const std::string& encoding) {
  RawFrame frame;
  frame.width = width;
  frame.height = height;
  frame.step = step;
  frame.encoding = encoding;
  frame.data = data.data();
  frame.data_size = data.size();
  return frame;
}

TEST(ParseEncoding, AcceptsEverySupportedName) {
  EXPECT_EQ(parseEncoding("bgr8"), Encoding::kBgr8);
  EXPECT_EQ(parseEncoding("rgb8"), Encoding::kRgb8);
  EXPECT_EQ(parseEncoding("bgra8"), Encoding::kBgra8);
  EXPECT_EQ(parseEncoding("rgba8"), Encoding::kRgba8);
  EXPECT_EQ(parseEncoding("mono8"), Encoding::kMono8);
  EXPECT_EQ(parseEncoding("mono16"), Encoding::kMono16);
  EXPECT_EQ(parseEncoding("8UC1"), Encoding::kMono8);
  EXPECT_EQ(parseEncoding("8UC3"), Encoding::kBgr8);
}

TEST(ParseEncoding, RejectsOthers) {
  for (const char* name : {"bayer_rggb8", "32FC1", "yuv422", "16UC3", "", "BGR8"}) {
    EXPECT_FALSE(parseEncoding(name).has_value()) << name;
  }
}

TEST(CheckFrame, AnUnsupportedEncodingListsTheSupportedOnes) {
  const std::vector<std::uint8_t> data(4 * 4, 0);
  EXPECT_EQ(checkFrame(frameOf(data, 4, 4, 4, "yuv422")).error,
            "unsupported encoding 'yuv422' (supported: bgr8, rgb8, bgra8, rgba8, mono8, mono16, "
            "8UC3, 8UC1)");
}

TEST(CheckFrame, AcceptsConsistentFrameWithRowPadding) {
  const std::vector<std::uint8_t> data(4 * 16, 0);  // 4 rows of 5 bgr pixels + 1 byte padding
  const FrameCheck check = checkFrame(frameOf(data, 5, 4, 16, "bgr8"));
  EXPECT_TRUE(check.ok()) << check.error;
  EXPECT_EQ(check.encoding, Encoding::kBgr8);
}

struct MalformedCase {
  const char* name;
  std::uint32_t width, height, step;
  std::size_t data_size;
  const char* encoding;
  const char* expected_words;
  FrameOutcome outcome;
};

class CheckFrameRejects : public ::testing::TestWithParam<MalformedCase> {};

TEST_P(CheckFrameRejects, NamesTheProblem) {
  const MalformedCase& c = GetParam();
  const std::vector<std::uint8_t> data(c.data_size, 0);
  const FrameCheck check = checkFrame(frameOf(data, c.width, c.height, c.step, c.encoding));
  ASSERT_FALSE(check.ok());
  EXPECT_NE(check.error.find(c.expected_words), std::string::npos) << check.error;
  EXPECT_EQ(check.outcome, c.outcome) << check.error;
}

INSTANTIATE_TEST_SUITE_P(
    Malformed, CheckFrameRejects,
    ::testing::Values(
        MalformedCase{"zero_width", 0, 4, 0, 0, "bgr8", "empty image", FrameOutcome::kBadSize},
        MalformedCase{"zero_height", 4, 0, 12, 0, "bgr8", "empty image", FrameOutcome::kBadSize},
        MalformedCase{"short_step", 4, 4, 11, 44, "bgr8", "step 11", FrameOutcome::kBadSize},
        MalformedCase{"short_step_mono16", 4, 4, 4, 16, "mono16", "step 4", FrameOutcome::kBadSize},
        // cv::Mat throws on a 16-bit row that is not a whole number of values.
        MalformedCase{"odd_step_mono16", 8, 4, 17, 68, "mono16",
                      "step 17 is not a multiple of 2 bytes", FrameOutcome::kBadSize},
        MalformedCase{"truncated", 4, 4, 12, 47, "bgr8", "data size 47", FrameOutcome::kBadSize},
        MalformedCase{"oversized", 4, 4, 12, 49, "bgr8", "data size 49", FrameOutcome::kBadSize},
        MalformedCase{"absurd", 100000, 2, 300000, 600000, "bgr8", "absurd dimensions",
                      FrameOutcome::kBadSize},
        MalformedCase{"bayer", 4, 4, 4, 16, "bayer_rggb8", "unsupported encoding",
                      FrameOutcome::kBadEncoding},
        MalformedCase{"float", 4, 4, 16, 64, "32FC1", "unsupported encoding",
                      FrameOutcome::kBadEncoding},
        MalformedCase{"yuv", 4, 4, 8, 32, "yuv422", "unsupported encoding",
                      FrameOutcome::kBadEncoding}),
    [](const ::testing::TestParamInfo<MalformedCase>& info) { return info.param.name; });

// One pixel with blue 10, green 20, red 30 in every colour encoding must come out identical.
TEST(ToBgr8, NormalisesEveryColourEncoding) {
  const cv::Vec3b expected(10, 20, 30);
  const std::vector<std::pair<Encoding, cv::Mat>> inputs = {
      {Encoding::kBgr8, cv::Mat(2, 3, CV_8UC3, cv::Scalar(10, 20, 30))},
      {Encoding::kRgb8, cv::Mat(2, 3, CV_8UC3, cv::Scalar(30, 20, 10))},
      {Encoding::kBgra8, cv::Mat(2, 3, CV_8UC4, cv::Scalar(10, 20, 30, 99))},
      {Encoding::kRgba8, cv::Mat(2, 3, CV_8UC4, cv::Scalar(30, 20, 10, 99))},
  };
  for (const auto& [encoding, image] : inputs) {
    const cv::Mat bgr = toBgr8(image, encoding);
    ASSERT_EQ(bgr.type(), CV_8UC3);
    ASSERT_EQ(bgr.size(), image.size());
    for (int r = 0; r < bgr.rows; ++r) {
      for (int c = 0; c < bgr.cols; ++c) {
        EXPECT_EQ(bgr.at<cv::Vec3b>(r, c), expected) << static_cast<int>(encoding);
      }
    }
  }
}

TEST(ToBgr8, NormalisesGreyEncodings) {
  const cv::Mat mono8(2, 3, CV_8UC1, cv::Scalar(77));
  const cv::Mat mono16(2, 3, CV_16UC1, cv::Scalar(77 * 256));
  const cv::Mat full16(2, 3, CV_16UC1, cv::Scalar(65535));
  EXPECT_EQ(toBgr8(mono8, Encoding::kMono8).at<cv::Vec3b>(1, 2), cv::Vec3b(77, 77, 77));
  EXPECT_EQ(toBgr8(mono16, Encoding::kMono16).at<cv::Vec3b>(1, 2), cv::Vec3b(77, 77, 77));
  EXPECT_EQ(toBgr8(full16, Encoding::kMono16).at<cv::Vec3b>(0, 0), cv::Vec3b(255, 255, 255));
}

TEST(CheckFrame, PaddedMono16RowsAndEveryStampAreAccepted) {
  const std::vector<std::uint8_t> data(4 * 18, 0);
  RawFrame frame = frameOf(data, 8, 4, 18, "mono16");  // one 2-byte value of padding per row
  frame.stamp_sec = 0xFFFFFFFFu;
  frame.stamp_nsec = 999999999u;
  EXPECT_TRUE(checkFrame(frame).ok()) << checkFrame(frame).error;
  EXPECT_EQ(checkFrame(frame).outcome, FrameOutcome::kAccepted);
  frame.stamp_nsec = 1000000000u;
  EXPECT_NE(checkFrame(frame).error.find("nanoseconds 1000000000"), std::string::npos);
  EXPECT_EQ(checkFrame(frame).outcome, FrameOutcome::kBadStamp);
}

TEST(FrameCounts, EachFrameOnceUnderItsOutcome) {
  FrameCounts counts;
  for (const FrameOutcome outcome :
       {FrameOutcome::kAccepted, FrameOutcome::kAccepted, FrameOutcome::kBadEncoding,
        FrameOutcome::kBadSize, FrameOutcome::kBadSize, FrameOutcome::kBadSize,
        FrameOutcome::kBadStamp, FrameOutcome::kSizeMismatch, FrameOutcome::kError}) {
    counts.countFrame(outcome);
  }
  counts.countCameraInfo(true);
  counts.countCameraInfo(false);
  counts.countCameraInfo(false);
  EXPECT_EQ(counts.framesDropped(), 7);
  const std::vector<std::pair<std::string, long>> expected = {
      {"frames_accepted", 2},   {"dropped_bad_encoding", 1},  {"dropped_bad_size", 3},
      {"dropped_bad_stamp", 1}, {"dropped_size_mismatch", 1}, {"dropped_error", 1}};
  EXPECT_EQ(counts.frameValues(), expected);
  const std::vector<std::pair<std::string, long>> camera_info = {{"camera_info_accepted", 1},
                                                                 {"dropped_bad_camera_info", 2}};
  EXPECT_EQ(counts.cameraInfoValues(), camera_info);
}

TEST(FrameToBgr8, SwapsBigEndianMono16) {
  // Two rows of 2 pixels (one 2-byte pad per row): 0x4D01 and 0xFF00 big-endian, i.e. 77, 255.
  const std::vector<std::uint8_t> data = {0x4D, 0x01, 0xFF, 0x00, 0, 0,
                                          0x4D, 0x01, 0xFF, 0x00, 0, 0};
  RawFrame frame = frameOf(data, 2, 2, 6, "mono16");
  frame.big_endian = true;
  ASSERT_TRUE(checkFrame(frame).ok());
  const cv::Mat bgr = frameToBgr8(frame, Encoding::kMono16);
  ASSERT_EQ(bgr.type(), CV_8UC3);
  EXPECT_EQ(bgr.at<cv::Vec3b>(1, 0), cv::Vec3b(77, 77, 77));
  EXPECT_EQ(bgr.at<cv::Vec3b>(1, 1), cv::Vec3b(255, 255, 255));
  frame.big_endian = false;  // the same bytes little-endian: 0x014D and 0x00FF
  EXPECT_EQ(frameToBgr8(frame, Encoding::kMono16).at<cv::Vec3b>(0, 0), cv::Vec3b(1, 1, 1));
  EXPECT_EQ(frameToBgr8(frame, Encoding::kMono16).at<cv::Vec3b>(0, 1), cv::Vec3b(1, 1, 1));
}

TEST(FrameToBgr8, ByteOrderDoesNotMatterForEightBitData) {
  const std::vector<std::uint8_t> data = {10, 20, 30, 10, 20, 30};
  RawFrame frame = frameOf(data, 2, 1, 6, "bgr8");
  frame.big_endian = true;
  EXPECT_EQ(frameToBgr8(frame, Encoding::kBgr8).at<cv::Vec3b>(0, 1), cv::Vec3b(10, 20, 30));
}

TEST(ToBgr8, AlwaysReturnsAFreshBuffer) {
  cv::Mat source(4, 4, CV_8UC3, cv::Scalar(1, 2, 3));
  const cv::Mat bgr = toBgr8(source, Encoding::kBgr8);
  EXPECT_NE(bgr.data, source.data);
}

TEST(Encoding, SizesMatchTheirOpenCvTypes) {
  for (Encoding e : {Encoding::kBgr8, Encoding::kRgb8, Encoding::kBgra8, Encoding::kRgba8,
                     Encoding::kMono8, Encoding::kMono16}) {
    EXPECT_EQ(static_cast<int>(CV_ELEM_SIZE(cvType(e))), bytesPerPixel(e));
    EXPECT_EQ(CV_MAT_CN(cvType(e)), channels(e));
  }
}

}  // namespace
}  // namespace follow_bot_common
