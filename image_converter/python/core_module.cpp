// image_converter.core: the ROS-free C++ overlay, feature matching and stitching from Python,
// with no logic of their own. Conventions: follow_bot_common/pybind_support.h.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot_common/pybind_support.h"
#include "image_converter/feature_matching.h"
#include "image_converter/overlay.h"
#include "image_converter/stitching.h"

namespace py = pybind11;
using namespace py::literals;

namespace image_converter {
namespace {

using namespace pybind_support;

// A cv::Mat view of an HxW grey or HxWx3 BGR uint8 array (matching takes either).
cv::Mat greyOrBgrView(const py::handle& image) {
  const bool grey =
      py::isinstance<py::array>(image) && py::reinterpret_borrow<py::array>(image).ndim() == 2;
  return matView(image, grey ? 1 : 3);
}

// `run` (matchPair, stitchPair) as Python calls it: on views of two images A and B (HxW grey or
// HxWx3 BGR uint8), without the GIL while it works.
template <class Result>
auto onImagePair(Result (*run)(const cv::Mat&, const cv::Mat&, const MatchOptions&)) {
  return [run](const py::handle& a, const py::handle& b, const MatchOptions& options) {
    const cv::Mat view_a = greyOrBgrView(a);
    const cv::Mat view_b = greyOrBgrView(b);
    py::gil_scoped_release unlocked;
    return run(view_a, view_b, options);
  };
}

// Raises ValueError with the validate() message of a config changed after construction.
template <class T>
void check(const T& config) {
  const std::string error = validate(config);
  if (!error.empty()) throw py::value_error(error);
}

void bindOverlay(py::module_& m) {
  py::class_<OverlayConfig> config(m, "OverlayConfig", "The lecture's red circle at the centre.");
  bindFields(config);
  defKeywordInit(config, static_cast<Validator<OverlayConfig>>(&validate));
  m.def(
      "draw_overlay",
      [](const py::handle& bgr, const OverlayConfig& config) {
        check(config);
        cv::Mat frame = matView(bgr, 3, true);
        return drawOverlay(frame, config);
      },
      "bgr"_a, "config"_a = OverlayConfig(),
      "Draws the circle onto the HxWx3 uint8 BGR array in place; False (untouched) when the "
      "image is not larger than min_image_size both ways.");
}

void bindMatching(py::module_& m) {
  py::enum_<Detector> detector(m, "Detector");
  defEnumNames(detector, kDetectorNames);

  py::class_<MatchOptions> options(m, "MatchOptions");
  defEnumField(options, "detector", &MatchOptions::detector, kDetectorNames);
  bindFields(options);
  defKeywordInit(options, static_cast<Validator<MatchOptions>>(&validate));

  py::class_<PairMatch> pair(m, "PairMatch",
                             "The homography mapping pixels of image B into image A, or why "
                             "there is none (error).");
  pair.def_readonly("error", &PairMatch::error)
      .def_property_readonly(
          "homography", [](const PairMatch& p) { return matrixArray(p.homography); }, "3x3")
      .def_readonly("keypoints_a", &PairMatch::keypoints_a)
      .def_readonly("keypoints_b", &PairMatch::keypoints_b)
      .def_readonly("matches", &PairMatch::matches)
      .def_readonly("inliers", &PairMatch::inliers)
      .def_readonly("reprojection_error_px", &PairMatch::reprojection_error_px)
      .def_readonly("refined", &PairMatch::refined)
      .def_readonly("held_out_matches", &PairMatch::held_out_matches)
      .def_readonly("held_out_median_ransac_px", &PairMatch::held_out_median_ransac_px)
      .def_readonly("held_out_median_refined_px", &PairMatch::held_out_median_refined_px)
      .def_property_readonly("ok", &PairMatch::ok);
  defRepr(pair);

  m.def("match_pair", onImagePair(&matchPair), "a"_a, "b"_a, "options"_a = MatchOptions(),
        "Matches image B against image A (HxW grey or HxWx3 BGR uint8); never raises on bad "
        "images, the result carries the error.");
  m.def(
      "apply_homography",
      [](const py::array_t<double, py::array::forcecast>& homography,
         const std::pair<double, double>& point) {
        if (homography.ndim() != 2 || homography.shape(0) != 3 || homography.shape(1) != 3) {
          throw py::value_error("homography must be 3x3, got shape " + shapeOf(homography));
        }
        const auto h = homography.unchecked<2>();
        cv::Matx33d matrix;
        for (int i = 0; i < 9; ++i) matrix(i / 3, i % 3) = h(i / 3, i % 3);
        return pointTuple(applyHomography(matrix, {point.first, point.second}));
      },
      "homography"_a, "point"_a, "The pixel (x, y) a 3x3 homography maps `point` to.");
}

void bindStitching(py::module_& m) {
  py::class_<StitchResult> result(m, "StitchResult");
  result.def_readonly("error", &StitchResult::error)
      .def_property_readonly(
          "panorama", [](const StitchResult& r) { return toArray(r.panorama); },
          "HxWx3 uint8 BGR (a new array each time)")
      .def_property_readonly(
          "origin_of_first", [](const StitchResult& r) { return pointTuple(r.origin_of_first); },
          "(x, y) px: where the first image's pixel (0, 0) landed")
      .def_readonly("pairs", &StitchResult::pairs)
      .def_property_readonly("ok", &StitchResult::ok);
  defRepr(result);
  m.attr("MAX_PANORAMA_SIDE") = kMaxPanoramaSide;

  m.def("stitch_pair", onImagePair(&stitchPair), "a"_a, "b"_a, "options"_a = MatchOptions(),
        "B warped into A's frame by match_pair's homography, the overlap feathered.");
  m.def(
      "stitch_many",
      [](const std::vector<py::handle>& images, const MatchOptions& options) {
        std::vector<cv::Mat> views;
        views.reserve(images.size());
        for (const py::handle& image : images) views.push_back(greyOrBgrView(image));
        py::gil_scoped_release unlocked;
        return stitchMany(views, options);
      },
      "images"_a, "options"_a = MatchOptions(),
      "Images left to right through cv::Stitcher (panorama mode).");

  py::class_<TurningCamera> camera(m, "TurningCamera",
                                   "A pinhole camera turned about the vertical axis; px and rad.");
  camera.def_readwrite("fx", &TurningCamera::fx)
      .def_readwrite("fy", &TurningCamera::fy)
      .def_readwrite("cx", &TurningCamera::cx)
      .def_readwrite("cy", &TurningCamera::cy)
      .def_readwrite("pitch", &TurningCamera::pitch);
  defKeywordInit(camera, static_cast<Validator<TurningCamera>>(&validate));
  m.def(
      "stitch_by_rotation",
      [](const std::vector<py::handle>& images, const std::vector<double>& yaws,
         const TurningCamera& camera) {
        std::vector<cv::Mat> views;
        views.reserve(images.size());
        for (const py::handle& image : images) views.push_back(matView(image, 3));
        py::gil_scoped_release unlocked;
        return stitchByRotation(views, yaws, camera);
      },
      "images"_a, "yaws"_a, "camera"_a,
      "Views of a camera turning in place stitched by their known yaws (rad, CCW), no features.");
}

}  // namespace
}  // namespace image_converter

PYBIND11_MODULE(core, m) {
  m.doc() = "image_converter's C++ overlay, feature matching and stitching for Python.";
  image_converter::bindOverlay(m);
  image_converter::bindMatching(m);
  image_converter::bindStitching(m);
}
