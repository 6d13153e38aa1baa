// pybind11 helpers shared by the Python modules image_converter.core and follow_bot.core (their
// python/ directories): numpy frames as cv::Mat views, configs as keyword constructors checked by
// the C++ validate(), results with a field-listing repr. Include only from a pybind11 module.
//
// Conventions (follow_bot/doc/python.md, "From Python"):
//  * frames are numpy uint8 arrays, HxWx3 BGR or HxW grey; the C++ code reads them in place
//    through a cv::Mat header (rows may be strided, e.g. a crop `frame[200:, 100:540]`; pixels
//    within a row must be packed). Anything else raises TypeError (dtype) or ValueError (shape,
//    layout) before C++ sees it;
//  * configs are classes with the C++ field names, built from keyword arguments and checked by
//    the C++ validate(): a bad value raises ValueError with its message;
//  * results are classes with the C++ field names and units; points are tuples, rectangles
//    (x, y, width, height), contours, corners and matrices numpy arrays;
//  * C++ camelCase methods are snake_case in Python (frameArrived -> frame_arrived).
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot_common/config_fields.h"
#include "follow_bot_common/enum_names.h"

namespace pybind_support {

namespace py = pybind11;

// ---- numpy <-> cv::Mat ---------------------------------------------------------------------

inline std::string shapeOf(const py::array& array) {
  return py::str(py::tuple(array.attr("shape"))).cast<std::string>();
}

// A cv::Mat header over the pixels of `frame` (no copy): an HxW (channels 1; HxWx1 too) or
// HxWxC uint8 array whose pixels are packed within each row.
inline cv::Mat matView(const py::handle& object, int channels, bool writable = false) {
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
inline py::array_t<std::uint8_t> toArray(const cv::Mat& image) {
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
inline std::string reprFields(const py::object& self) {
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

// A read-write attribute for each field T::fields() lists (config_fields.h), named as in C++,
// and the class attribute CFG_FIELDS: (field, .cfg parameter, scale) for each field a .cfg
// parameter sets, so Python maps ~params to a core's config as the nodelets do.
template <class T>
void bindFields(py::class_<T>& cls) {
  py::list cfg_fields;
  follow_bot_common::forEachField<T>([&](const auto& field) {
    cls.def_readwrite(field.name, field.member);
    if (field.cfg_param != nullptr) {
      cfg_fields.append(py::make_tuple(field.name, field.cfg_param, field.cfg_scale));
    }
  });
  cls.attr("CFG_FIELDS") = py::tuple(cfg_fields);
}

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

inline py::tuple pointTuple(const cv::Point2d& point) { return py::make_tuple(point.x, point.y); }

inline cv::Point2d pointFrom(const std::pair<double, double>& xy) { return {xy.first, xy.second}; }

// A 2-D float64 array copy of a small fixed matrix.
template <int Rows, int Cols>
py::array_t<double> matrixArray(const cv::Matx<double, Rows, Cols>& m) {
  py::array_t<double> out({Rows, Cols});
  for (int r = 0; r < Rows; ++r) {
    for (int c = 0; c < Cols; ++c) *out.mutable_data(r, c) = m(r, c);
  }
  return out;
}

// The enum's values under the names of its table (enum_names.h: the ~params' and ~status
// topics' spellings); E("name") parses one.
template <class E, std::size_t N>
void defEnumNames(py::enum_<E>& cls, const follow_bot_common::EnumName<E> (&names)[N]) {
  for (const follow_bot_common::EnumName<E>& entry : names) cls.value(entry.name, entry.value);
  const follow_bot_common::EnumName<E>(*table)[N] = &names;  // a static table: outlives the module
  cls.def(py::init([table](const std::string& name) {
    const std::optional<E> value = follow_bot_common::valueIn(*table, name);
    if (!value) throw py::value_error("unknown value '" + name + "'");
    return *value;
  }));
}

// A config field of enum type E that also takes the value's name (from its table): a str is
// parsed (ValueError naming the field for an unknown one), anything else must be an E.
template <class Config, class E, std::size_t N>
void defEnumField(py::class_<Config>& cls, const char* name, E Config::*field,
                  const follow_bot_common::EnumName<E> (&names)[N]) {
  const std::string field_name = name;
  const follow_bot_common::EnumName<E>(*table)[N] = &names;  // a static table: outlives the module
  cls.def_property(
      name, [field](const Config& config) { return config.*field; },
      [field, table, field_name](Config& config, const py::object& value) {
        if (!py::isinstance<py::str>(value)) {
          config.*field = value.cast<E>();
          return;
        }
        const std::optional<E> parsed =
            follow_bot_common::valueIn(*table, value.cast<std::string>());
        if (!parsed) {
          throw py::value_error(field_name + ": unknown value '" + value.cast<std::string>() + "'");
        }
        config.*field = *parsed;
      });
}

}  // namespace pybind_support
