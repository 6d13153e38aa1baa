// follow_bot.core: the ROS-free C++ cores from Python, with no logic of their own.
//
// Conventions (follow_bot/README.md, "From Python"):
//  * frames are numpy uint8 arrays, HxWx3 BGR or HxW grey; the C++ code reads them in place
//    through a cv::Mat header (rows may be strided, e.g. a crop `frame[200:, 100:540]`; pixels
//    within a row must be packed). Anything else raises TypeError (dtype) or ValueError (shape,
//    layout) before C++ sees it;
//  * configs are classes with the C++ field names, built from keyword arguments and checked by
//    the C++ validate(): a bad value raises ValueError with its message. So do the detectors'
//    and controllers' constructors, which run the same validate();
//  * results are classes with the C++ field names and units; points are tuples, rectangles
//    (x, y, width, height), contours, corners and rotations numpy arrays;
//  * C++ camelCase methods are snake_case here (frameArrived -> frame_arrived).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot/beacon_controller.h"
#include "follow_bot/colour_blobs.h"
#include "follow_bot/frame_watchdog.h"
#include "follow_bot/ground_projection.h"
#include "follow_bot/line_detector.h"
#include "follow_bot/tag_detector.h"
#include "follow_bot/velocity_limiter.h"

namespace py = pybind11;
using namespace py::literals;

namespace follow_bot {
namespace {

// ---- numpy <-> cv::Mat ---------------------------------------------------------------------

std::string shapeOf(const py::array& array) {
  return py::str(py::tuple(array.attr("shape"))).cast<std::string>();
}

// A cv::Mat header over the pixels of `frame` (no copy): an HxW (channels 1; HxWx1 too) or
// HxWxC uint8 array whose pixels are packed within each row.
cv::Mat matView(const py::handle& object, int channels, bool writable = false) {
  const char* expected = channels == 3 ? "an HxWx3 uint8 BGR array" : "an HxW uint8 grey array";
  // A plain isinstance check: the py::array argument caster would convert any sequence first.
  if (!py::isinstance<py::array>(object)) {
    throw py::type_error(std::string("expected ") + expected + " (numpy), got " +
                         py::type::of(object).attr("__name__").cast<std::string>());
  }
  const auto frame = py::reinterpret_borrow<py::array>(object);
  if (frame.dtype().kind() != 'u' || frame.dtype().itemsize() != 1) {
    throw py::type_error(std::string("expected ") + expected + ", got dtype " +
                         py::str(frame.dtype()).cast<std::string>());
  }
  const bool grey_shape =
      channels == 1 && (frame.ndim() == 2 || (frame.ndim() == 3 && frame.shape(2) == 1));
  const bool colour_shape = channels == 3 && frame.ndim() == 3 && frame.shape(2) == 3;
  if (!grey_shape && !colour_shape) {
    throw py::value_error(std::string("expected ") + expected + ", got shape " + shapeOf(frame));
  }
  const auto rows = frame.shape(0);
  const auto cols = frame.shape(1);
  if (rows == 0 || cols == 0) return cv::Mat();  // the C++ core reports an empty frame itself
  const bool packed = (frame.ndim() == 2 || frame.strides(2) == 1) &&
                      frame.strides(1) == channels && frame.strides(0) >= cols * channels;
  if (!packed) {
    throw py::value_error(std::string("expected ") + expected +
                          " with packed rows (pixels next to each other, rows top to bottom), got "
                          "strides " +
                          py::str(py::tuple(frame.attr("strides"))).cast<std::string>() +
                          "; pass numpy.ascontiguousarray(frame)");
  }
  if (writable && !frame.writeable()) throw py::value_error("the frame array is read-only");
  // cv::Mat takes a non-const pointer; the const uses of this view never write through it.
  auto* data = static_cast<unsigned char*>(const_cast<void*>(frame.data()));
  return cv::Mat(static_cast<int>(rows), static_cast<int>(cols), CV_8UC(channels), data,
                 static_cast<size_t>(frame.strides(0)));
}

// A new numpy array holding a copy of a CV_8UC1 or CV_8UC3 image (empty: shape (0, 0)).
py::array_t<std::uint8_t> toArray(const cv::Mat& image) {
  std::vector<py::ssize_t> shape{image.rows, image.cols};
  if (image.channels() > 1) shape.push_back(image.channels());
  py::array_t<std::uint8_t> out(shape);
  const size_t row_bytes = static_cast<size_t>(image.cols) * image.elemSize();
  for (int y = 0; y < image.rows; ++y) {
    std::memcpy(out.mutable_data(y), image.ptr(y), row_bytes);
  }
  return out;
}

// ---- configs and results -------------------------------------------------------------------

// "Name(field=value, ...)" over the class's attributes (its properties, in definition order).
std::string reprFields(const py::object& self) {
  const py::object type = py::type::of(self);
  const py::object property = py::module_::import("builtins").attr("property");
  std::string text = type.attr("__name__").cast<std::string>() + "(";
  bool first = true;
  for (const auto item : type.attr("__dict__").cast<py::dict>()) {
    if (!py::isinstance(item.second, property)) continue;
    const auto name = item.first.cast<std::string>();
    text +=
        (first ? "" : ", ") + name + "=" + py::repr(self.attr(name.c_str())).cast<std::string>();
    first = false;
  }
  return text + ")";
}

template <class T>
using Validator = std::string (*)(const T&);

// A keyword constructor Config(field=value, ...): every other field keeps its C++ default, an
// unknown keyword raises TypeError, and the result must pass the C++ validate() (ValueError
// with its message otherwise). Also adds validate() (the message, "" when fine) and __repr__.
template <class T>
void defKeywordInit(py::class_<T>& cls, Validator<T> validator = nullptr) {
  cls.def(py::init([validator](const py::kwargs& fields) {
            py::object object = py::cast(T());
            const py::object type = py::type::of(object);
            const py::object property = py::module_::import("builtins").attr("property");
            for (const auto item : fields) {
              const auto name = item.first.cast<std::string>();
              const py::object attribute = py::getattr(type, name.c_str(), py::none());
              if (!py::isinstance(attribute, property)) {
                throw py::type_error(type.attr("__name__").cast<std::string>() +
                                     "() got an unexpected keyword argument '" + name + "'");
              }
              py::setattr(object, name.c_str(), item.second);
            }
            T config = object.cast<T>();
            if (validator) {
              const std::string error = validator(config);
              if (!error.empty()) throw py::value_error(error);
            }
            return config;
          }),
          "Keyword arguments set fields by name; the rest keep their C++ defaults.");
  if (validator) {
    cls.def(
        "validate", [validator](const T& config) { return validator(config); },
        "The C++ validate(): '' when usable, else a message naming the first bad field.");
  }
  cls.def("__repr__", &reprFields);
}

template <class T>
void defRepr(py::class_<T>& cls) {
  cls.def("__repr__", &reprFields);
}

py::tuple pointTuple(const cv::Point2d& point) { return py::make_tuple(point.x, point.y); }

cv::Point2d pointFrom(const std::pair<double, double>& xy) { return {xy.first, xy.second}; }

// A 2-D float64 array copy of a small fixed matrix.
template <int Rows, int Cols>
py::array_t<double> matrixArray(const cv::Matx<double, Rows, Cols>& m) {
  py::array_t<double> out({Rows, Cols});
  for (int r = 0; r < Rows; ++r) {
    for (int c = 0; c < Cols; ++c) *out.mutable_data(r, c) = m(r, c);
  }
  return out;
}

// ---- bindings --------------------------------------------------------------------------------

void bindVelocity(py::module_& m) {
  py::class_<Twist2D> twist(m, "Twist2D",
                            "A planar command (REP-103): linear m/s forward, angular rad/s, "
                            "positive = turning left.");
  twist.def_readwrite("linear", &Twist2D::linear).def_readwrite("angular", &Twist2D::angular);
  defKeywordInit(twist);

  py::class_<VelocityLimiterConfig> config(m, "VelocityLimiterConfig");
  config.def_readwrite("max_linear", &VelocityLimiterConfig::max_linear)
      .def_readwrite("max_angular", &VelocityLimiterConfig::max_angular)
      .def_readwrite("max_linear_accel", &VelocityLimiterConfig::max_linear_accel)
      .def_readwrite("max_angular_accel", &VelocityLimiterConfig::max_angular_accel)
      .def_readwrite("allow_reverse", &VelocityLimiterConfig::allow_reverse);
  defKeywordInit(config, static_cast<Validator<VelocityLimiterConfig>>(&validate));

  py::class_<VelocityLimiter>(m, "VelocityLimiter",
                              "Clamps and rate-limits velocity commands; never passes a NaN.")
      .def(py::init<const VelocityLimiterConfig&>(), "config"_a = VelocityLimiterConfig())
      .def("limit", &VelocityLimiter::limit, "desired"_a, "dt"_a,
           "The command to send, given the desired one and the seconds since the last call.")
      .def("stop", &VelocityLimiter::stop, "Immediate zero; the next limit() ramps up from rest.")
      .def("reset", &VelocityLimiter::reset, "Forgets the previous output (robot at rest).")
      .def_property_readonly("last_output", [](const VelocityLimiter& l) { return l.lastOutput(); })
      .def_property_readonly(
          "config", [](const VelocityLimiter& l) { return l.config(); }, "A copy of the config.");
}

void bindWatchdog(py::module_& m) {
  py::class_<FrameWatchdog>(m, "FrameWatchdog",
                            "Tracks frame arrival times (seconds, one clock) to detect a stalled "
                            "camera.")
      .def(py::init<double>(), "timeout_s"_a)
      .def("frame_arrived", &FrameWatchdog::frameArrived, "t"_a)
      .def("expired", &FrameWatchdog::expired, "now"_a)
      .def("should_send_stop", &FrameWatchdog::shouldSendStop, "now"_a,
           "True exactly once per outage.")
      .def("reset", &FrameWatchdog::reset)
      .def_property_readonly("timeout", &FrameWatchdog::timeout)
      .def_property_readonly("last_frame", &FrameWatchdog::lastFrame);
}

void bindLineDetector(py::module_& m) {
  py::class_<HsvColor> hsv(m, "HsvColor", "OpenCV 8-bit HSV: h 0..179 (degrees / 2), s, v 0..255.");
  hsv.def(py::init([](int h, int s, int v) {
            return HsvColor{h, s, v};
          }),
          "h"_a, "s"_a, "v"_a)
      .def_readwrite("h", &HsvColor::h)
      .def_readwrite("s", &HsvColor::s)
      .def_readwrite("v", &HsvColor::v);
  defKeywordInit(hsv);

  py::class_<BandConfig> band(m, "BandConfig",
                              "Rows [floor(top_fraction * height), that + rows) of the frame.");
  band.def_readwrite("top_fraction", &BandConfig::top_fraction)
      .def_readwrite("rows", &BandConfig::rows);
  defKeywordInit(band);

  py::class_<LineDetectorConfig> config(m, "LineDetectorConfig");
  config.def_readwrite("lower", &LineDetectorConfig::lower)
      .def_readwrite("upper", &LineDetectorConfig::upper)
      .def_readwrite("band", &LineDetectorConfig::band)
      .def_readwrite("look_ahead_enabled", &LineDetectorConfig::look_ahead_enabled)
      .def_readwrite("look_ahead", &LineDetectorConfig::look_ahead)
      .def_readwrite("min_pixels", &LineDetectorConfig::min_pixels)
      .def_readwrite("max_width_fraction", &LineDetectorConfig::max_width_fraction);
  defKeywordInit(config, static_cast<Validator<LineDetectorConfig>>(&validate));

  py::class_<BandMeasurement> measurement(m, "BandMeasurement");
  measurement.def_readonly("found", &BandMeasurement::found)
      .def_readonly("pixel_count", &BandMeasurement::pixel_count)
      .def_readonly("centroid_x", &BandMeasurement::centroid_x)
      .def_readonly("centroid_y", &BandMeasurement::centroid_y)
      .def_readonly("error_px", &BandMeasurement::error_px)
      .def_readonly("error_normalised", &BandMeasurement::error_normalised)
      .def_readonly("confidence", &BandMeasurement::confidence)
      .def_readonly("row_begin", &BandMeasurement::row_begin)
      .def_readonly("row_end", &BandMeasurement::row_end);
  defRepr(measurement);

  py::class_<LineMeasurement> line(m, "LineMeasurement");
  line.def_readonly("error", &LineMeasurement::error)
      .def_readonly("image_width", &LineMeasurement::image_width)
      .def_readonly("image_height", &LineMeasurement::image_height)
      .def_readonly("band", &LineMeasurement::band)
      .def_readonly("look_ahead", &LineMeasurement::look_ahead)
      .def_property_readonly("ok", &LineMeasurement::ok);
  defRepr(line);

  py::class_<LineDetector>(m, "LineDetector",
                           "The follower's floor-line detector: the lecture's HSV band centroid.")
      .def(py::init<const LineDetectorConfig&>(), "config"_a = LineDetectorConfig())
      .def(
          "detect",
          [](const LineDetector& detector, const py::handle& bgr,
             const std::optional<LineMeasurement>& previous) {
            const cv::Mat frame = matView(bgr, 3);
            py::gil_scoped_release unlocked;
            return previous ? detector.detect(frame, *previous) : detector.detect(frame);
          },
          "bgr"_a, "previous"_a = py::none(),
          "The line in an HxWx3 uint8 BGR frame; with `previous` (the last measurement), only "
          "the band's blob nearest its sighting.")
      .def(
          "debug_mask",
          [](const LineDetector& detector, const py::handle& bgr) {
            return toArray(detector.debugMask(matView(bgr, 3)));
          },
          "bgr"_a, "HxW uint8: 255 on line pixels inside the band(s).")
      .def(
          "draw_debug",
          [](const LineDetector& detector, const py::handle& bgr,
             const LineMeasurement& measurement) {
            cv::Mat frame = matView(bgr, 3, true);
            return detector.drawDebug(frame, measurement);
          },
          "bgr"_a, "measurement"_a,
          "Draws the line pixels, bands and centroid onto the frame array, in place.")
      .def_property_readonly(
          "config", [](const LineDetector& d) { return d.config(); }, "A copy of the config.");
}

void bindColourBlobs(py::module_& m) {
  py::class_<ColourSpec> spec(
      m, "ColourSpec", "A hue window (centre +- sensitivity, wrapping) with S and V floors.");
  spec.def_readwrite("name", &ColourSpec::name)
      .def_readwrite("hue_centre", &ColourSpec::hue_centre)
      .def_readwrite("sensitivity", &ColourSpec::sensitivity)
      .def_readwrite("s_min", &ColourSpec::s_min)
      .def_readwrite("v_min", &ColourSpec::v_min);
  defKeywordInit(spec);
  m.def("parse_colour_name", &parseColourName, "name"_a,
        "The default ColourSpec of 'red', 'green' or 'blue'; None for other names.");

  py::class_<ColourBlobConfig> config(m, "ColourBlobConfig");
  config
      .def_readwrite("colours", &ColourBlobConfig::colours,
                     "A list (assign a new one to change it).")
      .def_readwrite("open_kernel", &ColourBlobConfig::open_kernel)
      .def_readwrite("close_kernel", &ColourBlobConfig::close_kernel)
      .def_readwrite("min_area", &ColourBlobConfig::min_area);
  defKeywordInit(config, static_cast<Validator<ColourBlobConfig>>(&validate));

  py::class_<ColourBlob> blob(m, "ColourBlob",
                              "The largest blob of one colour; pixel centres at integers.");
  blob.def_readwrite("name", &ColourBlob::name)
      .def_readwrite("found", &ColourBlob::found)
      .def_readwrite("blob_count", &ColourBlob::blob_count)
      .def_readwrite("area", &ColourBlob::area)
      .def_property(
          "centroid", [](const ColourBlob& b) { return pointTuple(b.centroid); },
          [](ColourBlob& b, const std::pair<double, double>& xy) { b.centroid = pointFrom(xy); },
          "(x, y) px")
      .def_property(
          "circle_centre",
          [](const ColourBlob& b) { return py::make_tuple(b.circle_centre.x, b.circle_centre.y); },
          [](ColourBlob& b, const std::pair<float, float>& xy) {
            b.circle_centre = {xy.first, xy.second};
          },
          "(x, y) px")
      .def_readwrite("circle_radius", &ColourBlob::circle_radius)
      .def_property(
          "bounding_box",
          [](const ColourBlob& b) {
            const cv::Rect& r = b.bounding_box;
            return py::make_tuple(r.x, r.y, r.width, r.height);
          },
          [](ColourBlob& b, const std::tuple<int, int, int, int>& r) {
            b.bounding_box = {std::get<0>(r), std::get<1>(r), std::get<2>(r), std::get<3>(r)};
          },
          "(x, y, width, height), inclusive pixels")
      .def_property(
          "contour",
          [](const ColourBlob& b) {
            py::array_t<int> out({static_cast<py::ssize_t>(b.contour.size()), py::ssize_t{2}});
            for (size_t i = 0; i < b.contour.size(); ++i) {
              *out.mutable_data(i, 0) = b.contour[i].x;
              *out.mutable_data(i, 1) = b.contour[i].y;
            }
            return out;
          },
          [](ColourBlob& b, const std::vector<std::pair<int, int>>& points) {
            b.contour.clear();
            for (const auto& [x, y] : points) b.contour.emplace_back(x, y);
          },
          "Nx2 int32 array of (x, y), every boundary pixel");
  defKeywordInit(blob);

  py::class_<BlobResult> result(m, "BlobResult");
  result.def_readwrite("error", &BlobResult::error)
      .def_readwrite("image_width", &BlobResult::image_width)
      .def_readwrite("image_height", &BlobResult::image_height)
      .def_readwrite("colours", &BlobResult::colours, "One ColourBlob per configured colour.")
      .def_property_readonly("ok", &BlobResult::ok)
      .def(
          "find",
          [](const BlobResult& r, const std::string& name) -> std::optional<ColourBlob> {
            const ColourBlob* found = r.find(name);
            if (found == nullptr) return std::nullopt;
            return *found;
          },
          "name"_a, "The blob of the named colour, or None when that colour is not configured.");
  defKeywordInit(result);

  py::class_<ColourBlobDetector>(m, "ColourBlobDetector",
                                 "The largest blob of each configured colour (Lab 5).")
      .def(py::init<const ColourBlobConfig&>(), "config"_a = ColourBlobConfig())
      .def(
          "detect",
          [](const ColourBlobDetector& detector, const py::handle& bgr) {
            const cv::Mat frame = matView(bgr, 3);
            py::gil_scoped_release unlocked;
            return detector.detect(frame);
          },
          "bgr"_a, "Every configured colour in an HxWx3 uint8 BGR frame.")
      .def(
          "mask",
          [](const ColourBlobDetector& detector, const py::handle& bgr, const std::string& name) {
            return toArray(detector.mask(matView(bgr, 3), name));
          },
          "bgr"_a, "name"_a, "HxW uint8: the cleaned-up mask the named colour's blobs are in.")
      .def_property_readonly(
          "config", [](const ColourBlobDetector& d) { return d.config(); },
          "A copy of the config.");
}

void bindGeometry(py::module_& m) {
  py::class_<CameraGeometry> camera(m, "CameraGeometry",
                                    "Pinhole intrinsics (px) and mounting (m, rad) of the camera.");
  camera.def_readwrite("fx", &CameraGeometry::fx)
      .def_readwrite("fy", &CameraGeometry::fy)
      .def_readwrite("cx", &CameraGeometry::cx)
      .def_readwrite("cy", &CameraGeometry::cy)
      .def_readwrite("height_m", &CameraGeometry::height_m)
      .def_readwrite("pitch_rad", &CameraGeometry::pitch_rad)
      .def_readwrite("x_offset_m", &CameraGeometry::x_offset_m);
  defKeywordInit(camera, static_cast<Validator<CameraGeometry>>(&validate));
}

// An enum whose values are the C++ names' ROS spellings; E("name") parses one.
template <class E>
void defStringInit(py::enum_<E>& cls, std::optional<E> (*parse)(const std::string&)) {
  cls.def(py::init([parse](const std::string& name) {
    const std::optional<E> value = parse(name);
    if (!value) throw py::value_error("unknown value '" + name + "'");
    return *value;
  }));
}

// A config field of enum type E that also takes the value's name: a str is parsed (ValueError
// naming the field for an unknown one), anything else must be an E.
template <class Config, class E>
void defEnumField(py::class_<Config>& cls, const char* name, E Config::*field,
                  std::optional<E> (*parse)(const std::string&)) {
  const std::string field_name = name;
  cls.def_property(
      name, [field](const Config& config) { return config.*field; },
      [field, parse, field_name](Config& config, const py::object& value) {
        if (!py::isinstance<py::str>(value)) {
          config.*field = value.cast<E>();
          return;
        }
        const std::optional<E> parsed = parse(value.cast<std::string>());
        if (!parsed) {
          throw py::value_error(field_name + ": unknown value '" + value.cast<std::string>() + "'");
        }
        config.*field = *parsed;
      });
}

void bindBeaconController(py::module_& m) {
  py::enum_<BeaconShape> shape(m, "BeaconShape");
  shape.value("sphere", BeaconShape::kSphere).value("box", BeaconShape::kBox);
  defStringInit(shape, &parseBeaconShape);

  py::class_<BeaconObject> object(m, "BeaconObject",
                                  "size_m: a sphere's radius, a box's width facing the camera.");
  defEnumField(object, "shape", &BeaconObject::shape, &parseBeaconShape);
  object.def_readwrite("size_m", &BeaconObject::size_m);
  defKeywordInit(object, static_cast<Validator<BeaconObject>>(&validate));

  py::class_<RangeEstimate> range(m, "RangeEstimate", "Ranges in m; None when not observable.");
  range.def_readonly("from_size", &RangeEstimate::from_size)
      .def_readonly("from_ground", &RangeEstimate::from_ground)
      .def("best", &RangeEstimate::best);
  defRepr(range);
  m.def("estimate_range", &estimateRange, "blob"_a, "image_width"_a, "image_height"_a, "camera"_a,
        "object"_a);

  py::enum_<BeaconMode> mode(m, "BeaconMode");
  mode.value("follow_green_stop_red", BeaconMode::kFollowGreenStopRed)
      .value("approach", BeaconMode::kApproach);
  defStringInit(mode, &parseBeaconMode);

  py::enum_<BeaconState>(m, "BeaconState")
      .value("SEARCHING", BeaconState::kSearching)
      .value("APPROACHING", BeaconState::kApproaching)
      .value("HOLDING", BeaconState::kHolding)
      .value("STOPPED_BY_RED", BeaconState::kStoppedByRed)
      .value("LOST", BeaconState::kLost)
      .value("ARRIVED", BeaconState::kArrived);

  using Config = BeaconControllerConfig;
  py::class_<Config> config(m, "BeaconControllerConfig");
  defEnumField(config, "mode", &Config::mode, &parseBeaconMode);
  config.def_readwrite("search_rate", &Config::search_rate)
      .def_readwrite("follow_colour", &Config::follow_colour)
      .def_readwrite("stop_colour", &Config::stop_colour)
      .def_readwrite("close_area", &Config::close_area)
      .def_readwrite("stop_min_area", &Config::stop_min_area)
      .def_readwrite("stop_release_delay", &Config::stop_release_delay)
      .def_readwrite("approach_speed", &Config::approach_speed)
      .def_readwrite("turn_gain", &Config::turn_gain)
      .def_readwrite("target_colour", &Config::target_colour)
      .def_readwrite("target", &Config::target)
      .def_readwrite("camera", &Config::camera)
      .def_readwrite("stop_distance", &Config::stop_distance)
      .def_readwrite("k_range", &Config::k_range)
      .def_readwrite("max_linear", &Config::max_linear)
      .def_readwrite("allow_reverse", &Config::allow_reverse)
      .def_readwrite("speed_taper_bearing", &Config::speed_taper_bearing)
      .def_readwrite("k_bearing", &Config::k_bearing)
      .def_readwrite("max_angular", &Config::max_angular)
      .def_readwrite("distance_tolerance", &Config::distance_tolerance)
      .def_readwrite("bearing_tolerance", &Config::bearing_tolerance)
      .def_readwrite("lost_hold", &Config::lost_hold);
  defKeywordInit(config, static_cast<Validator<Config>>(&validate));
  m.def("check_colours_detected", &checkColoursDetected, "controller"_a, "detector"_a,
        "'' when the detector measures every colour the controller uses, else a message.");

  py::class_<BeaconController>(m, "BeaconController",
                               "Lab 5's follow green / stop at red, or Exercise 10's approach.")
      .def(py::init<const Config&>(), "config"_a = Config())
      .def("update", &BeaconController::update, "blobs"_a, "stamp"_a,
           "The Twist2D for one frame's BlobResult; stamp in seconds.")
      .def_property_readonly("state", &BeaconController::state)
      .def_property_readonly("last_range", [](const BeaconController& c) { return c.lastRange(); })
      .def_property_readonly("last_bearing",
                             [](const BeaconController& c) { return c.lastBearing(); })
      .def_property_readonly(
          "config", [](const BeaconController& c) { return c.config(); }, "A copy of the config.")
      .def("reset", &BeaconController::reset);
}

void bindTagDetector(py::module_& m) {
  py::class_<TagDetectorConfig> config(m, "TagDetectorConfig");
  config.def_readwrite("family", &TagDetectorConfig::family)
      .def_readwrite("id", &TagDetectorConfig::id)
      .def_readwrite("size_m", &TagDetectorConfig::size_m)
      .def_readwrite("quad_decimate", &TagDetectorConfig::quad_decimate)
      .def_readwrite("min_decision_margin", &TagDetectorConfig::min_decision_margin)
      .def_readwrite("max_hamming", &TagDetectorConfig::max_hamming)
      .def_readwrite("ambiguity_ratio", &TagDetectorConfig::ambiguity_ratio)
      .def_readwrite("ambiguity_px", &TagDetectorConfig::ambiguity_px);
  defKeywordInit(config, static_cast<Validator<TagDetectorConfig>>(&validate));

  py::class_<MarkerObservation> observation(
      m, "MarkerObservation",
      "A marker's pose in the camera optical frame (x right, y down, z forward), metres.");
  observation.def_readonly("id", &MarkerObservation::id)
      .def_property_readonly(
          "corners",
          [](const MarkerObservation& o) {
            py::array_t<double> out({4, 2});
            for (int i = 0; i < 4; ++i) {
              *out.mutable_data(i, 0) = o.corners[i].x;
              *out.mutable_data(i, 1) = o.corners[i].y;
            }
            return out;
          },
          "4x2 px: TL, TR, BR, BL seen from the front")
      .def_property_readonly(
          "rotation", [](const MarkerObservation& o) { return matrixArray(o.rotation); }, "3x3")
      .def_property_readonly(
          "translation",
          [](const MarkerObservation& o) { return py::array_t<double>(3, o.translation.val); },
          "the marker centre, (3,)")
      .def_readonly("reprojection_error_px", &MarkerObservation::reprojection_error_px)
      .def_readonly("quality", &MarkerObservation::quality);
  defRepr(observation);

  py::class_<TagDetector>(
      m, "TagDetector",
      "The parker's AprilTag detector (libapriltag) and pose (IPPE + refinement).")
      .def(py::init<const TagDetectorConfig&>(), "config"_a = TagDetectorConfig())
      .def(
          "detect",
          [](TagDetector& detector, const py::handle& grey, const CameraGeometry& camera) {
            return detector.detect(matView(grey, 1), camera);
          },
          "grey"_a, "camera"_a = CameraGeometry(),
          "The configured tag in an HxW uint8 frame, or None; only the intrinsics are used. "
          "Stateful (the previous pose settles the planar ambiguity).")
      .def("reset", &TagDetector::reset, "Forgets the previous pose.")
      .def_property_readonly(
          "config", [](const TagDetector& d) { return d.config(); }, "A copy of the config.");
}

}  // namespace
}  // namespace follow_bot

PYBIND11_MODULE(core, m) {
  m.doc() = "follow_bot's C++ detectors and controllers (the nodes' own code) for Python.";
  follow_bot::bindVelocity(m);
  follow_bot::bindWatchdog(m);
  follow_bot::bindGeometry(m);
  follow_bot::bindLineDetector(m);
  follow_bot::bindColourBlobs(m);
  follow_bot::bindBeaconController(m);
  follow_bot::bindTagDetector(m);
}
