// The codec on exact pixels: PNG round trips are lossless, JPEG stays within a few grey levels on
// a smooth image, format strings match the upstream plugin's, malformed payloads are errors.
#include <gtest/gtest.h>

#include <string>

#include <opencv2/imgproc.hpp>

#include "compressed_transport/codec.h"

namespace compressed_transport {
namespace {

// A smooth BGR ramp with a distinct value per channel.
cv::Mat ramp(int rows = 48, int cols = 64) {
  cv::Mat image(rows, cols, CV_8UC3);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      image.at<cv::Vec3b>(r, c) = cv::Vec3b(static_cast<uchar>(2 * c), static_cast<uchar>(4 * r),
                                            static_cast<uchar>(100 + c / 2));
    }
  }
  return image;
}

double maxDifference(const cv::Mat& a, const cv::Mat& b) {
  double worst = 0.0;
  cv::minMaxLoc(cv::abs(a - b), nullptr, &worst);
  return worst;
}

EncoderConfig png() {
  EncoderConfig config;
  config.format = Format::kPng;
  return config;
}

// `image` (`encoding`) through PNG: the format string is `format`, and it decodes to the same
// encoding and the same pixels.
void expectExactPngRoundTrip(const cv::Mat& image, const std::string& encoding,
                             const std::string& format) {
  const Encoded encoded = encode(image, encoding, png());
  EXPECT_EQ(encoded.format, format);
  const Decoded decoded = decode(encoded.data, encoded.format);
  ASSERT_EQ(decoded.error, "");
  EXPECT_EQ(decoded.encoding, encoding);
  EXPECT_EQ(cv::norm(decoded.image, image, cv::NORM_INF), 0.0);
}

TEST(Codec, PngRoundTripIsExact) {
  expectExactPngRoundTrip(ramp(), "bgr8", "bgr8; png compressed bgr8");
}

TEST(Codec, RgbComesBackAsRgb) {
  cv::Mat rgb;
  cv::cvtColor(ramp(), rgb, cv::COLOR_BGR2RGB);
  expectExactPngRoundTrip(rgb, "rgb8", "rgb8; png compressed bgr8");
}

TEST(Codec, Mono16PngIsExact) {
  cv::Mat depth(10, 12, CV_16UC1);
  cv::randu(depth, 0, 65535);
  expectExactPngRoundTrip(depth, "mono16", "mono16; png compressed ");
}

TEST(Codec, JpegQualitySetsTheError) {
  const cv::Mat image = ramp();
  EncoderConfig config;
  config.jpeg_quality = 95;
  const Encoded fine = encode(image, "bgr8", config);
  EXPECT_EQ(fine.format, "bgr8; jpeg compressed bgr8");
  config.jpeg_quality = 10;
  const Encoded coarse = encode(image, "bgr8", config);
  EXPECT_LT(coarse.data.size(), fine.data.size());
  const Decoded fine_back = decode(fine.data, fine.format);
  const Decoded coarse_back = decode(coarse.data, coarse.format);
  EXPECT_LE(maxDifference(fine_back.image, image), 8.0);
  EXPECT_GT(maxDifference(coarse_back.image, image), maxDifference(fine_back.image, image));
}

TEST(Codec, JpegRefusesSixteenBits) {
  EXPECT_THROW(encode(cv::Mat(4, 4, CV_16UC1, cv::Scalar(0)), "mono16", EncoderConfig()),
               std::invalid_argument);
  EXPECT_THROW(encode(ramp(), "yuv422", png()), std::invalid_argument);
}

TEST(Codec, OldFormatStringsDecodeAsBgrOrMono) {
  const Encoded encoded = encode(ramp(), "bgr8", png());
  const Decoded decoded = decode(encoded.data, "png");
  EXPECT_EQ(decoded.encoding, "bgr8");
  EXPECT_EQ(decoded.image.channels(), 3);
}

TEST(Codec, MalformedPayloadsAreErrors) {
  EXPECT_EQ(decode({}, "bgr8; jpeg compressed bgr8").error, "empty payload");
  const Decoded garbage = decode({0xff, 0xd8, 0x00, 0x13, 0x37}, "bgr8; jpeg compressed bgr8");
  EXPECT_TRUE(garbage.image.empty());
  EXPECT_NE(garbage.error.find("undecodable payload"), std::string::npos) << garbage.error;
  Encoded truncated = encode(ramp(), "bgr8", EncoderConfig());
  truncated.data.resize(20);
  EXPECT_TRUE(decode(truncated.data, truncated.format).image.empty());
  const Encoded fine = encode(ramp(), "bgr8", png());
  const Decoded odd = decode(fine.data, "yuv422; png compressed bgr8");
  EXPECT_EQ(odd.error, "unsupported encoding 'yuv422' in format 'yuv422; png compressed bgr8'");
}

TEST(Codec, ConfigNamesTheBadParameter) {
  EncoderConfig config;
  EXPECT_EQ(config.validate(), "");
  config.jpeg_quality = 0;
  EXPECT_EQ(config.validate(), "jpeg_quality must be in [1, 100], got 0");
  config = EncoderConfig();
  config.png_level = 10;
  EXPECT_EQ(config.validate(), "png_level must be in [0, 9], got 10");
  EXPECT_THROW(parseFormat("webp"), std::invalid_argument);
  EXPECT_EQ(parseFormat("png"), Format::kPng);
}

}  // namespace
}  // namespace compressed_transport
