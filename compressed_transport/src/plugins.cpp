// The `compressed` image_transport plugins: thin ROS shells around codec.h.
//
// Publisher: `<base>/compressed` (sensor_msgs/CompressedImage); parameters under that topic's
// namespace, as upstream: `format` (jpeg|png, default jpeg), `jpeg_quality` (1-100, 95),
// `png_level` (0-9, 9), read when the topic is advertised (a bad value is an error there).
// Subscriber: decodes each message into a sensor_msgs/Image for the user's callback; a malformed
// payload is a throttled error and the frame is dropped.
#include <stdexcept>
#include <string>

#include <image_transport/simple_publisher_plugin.h>
#include <image_transport/simple_subscriber_plugin.h>
#include <ros/ros.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>
#include <pluginlib/class_list_macros.hpp>

#include "compressed_transport/codec.h"

namespace compressed_transport {

namespace {
constexpr char kTransport[] = "compressed";

// A view of the message's pixels (no copy); throws std::invalid_argument when the buffer does
// not hold height x step bytes.
cv::Mat pixelsOf(const sensor_msgs::Image& image) {
  namespace enc = sensor_msgs::image_encodings;
  const int depth = enc::bitDepth(image.encoding) == 16 ? CV_16U : CV_8U;
  const int type = CV_MAKETYPE(depth, enc::numChannels(image.encoding));
  if (image.data.size() < static_cast<size_t>(image.height) * image.step) {
    throw std::invalid_argument("image data shorter than height x step");
  }
  return cv::Mat(image.height, image.width, type, const_cast<uint8_t*>(image.data.data()),
                 image.step);
}
}  // namespace

class CompressedPublisher
    : public image_transport::SimplePublisherPlugin<sensor_msgs::CompressedImage> {
 public:
  std::string getTransportName() const override { return kTransport; }

 protected:
  void advertiseImpl(ros::NodeHandle& nh, const std::string& base_topic, uint32_t queue_size,
                     const image_transport::SubscriberStatusCallback& connect_cb,
                     const image_transport::SubscriberStatusCallback& disconnect_cb,
                     const ros::VoidPtr& tracked_object, bool latch) override {
    SimplePublisherPlugin::advertiseImpl(nh, base_topic, queue_size, connect_cb, disconnect_cb,
                                         tracked_object, latch);
    const std::string where = nh.resolveName(base_topic) + "/" + kTransport + "/";
    config_.format = parseFormat(this->nh().param<std::string>("format", "jpeg"));
    config_.jpeg_quality = this->nh().param("jpeg_quality", config_.jpeg_quality);
    config_.png_level = this->nh().param("png_level", config_.png_level);
    const std::string error = config_.validate();
    if (!error.empty()) throw std::invalid_argument(where + error);
  }

  void publish(const sensor_msgs::Image& image, const PublishFn& publish_fn) const override {
    try {
      Encoded encoded = encode(pixelsOf(image), image.encoding, config_);
      sensor_msgs::CompressedImage message;
      message.header = image.header;
      message.format = std::move(encoded.format);
      message.data = std::move(encoded.data);
      publish_fn(message);
    } catch (const std::exception& error) {  // cv::Exception too
      ROS_ERROR_THROTTLE(5.0, "compressed publisher on %s: frame not sent: %s", getTopic().c_str(),
                         error.what());
    }
  }

 private:
  EncoderConfig config_;
};

class CompressedSubscriber
    : public image_transport::SimpleSubscriberPlugin<sensor_msgs::CompressedImage> {
 public:
  std::string getTransportName() const override { return kTransport; }

 protected:
  void internalCallback(const sensor_msgs::CompressedImageConstPtr& message,
                        const Callback& user_cb) override {
    const Decoded decoded = decode(message->data, message->format);
    if (decoded.image.empty()) {
      ROS_ERROR_THROTTLE(5.0, "compressed subscriber on %s: frame dropped: %s", getTopic().c_str(),
                         decoded.error.c_str());
      return;
    }
    const sensor_msgs::ImagePtr image = boost::make_shared<sensor_msgs::Image>();
    image->header = message->header;
    image->height = decoded.image.rows;
    image->width = decoded.image.cols;
    image->encoding = decoded.encoding;
    image->is_bigendian = false;
    image->step = static_cast<uint32_t>(decoded.image.cols * decoded.image.elemSize());
    const cv::Mat contiguous = decoded.image.isContinuous() ? decoded.image : decoded.image.clone();
    image->data.assign(contiguous.datastart, contiguous.dataend);
    user_cb(image);
  }
};

}  // namespace compressed_transport

PLUGINLIB_EXPORT_CLASS(compressed_transport::CompressedPublisher, image_transport::PublisherPlugin)
PLUGINLIB_EXPORT_CLASS(compressed_transport::CompressedSubscriber,
                       image_transport::SubscriberPlugin)
