// The C++ side of tests/bindings/test_python_core.py for image_converter.core: runs the overlay,
// pair matching or stitching on image files and prints one JSON line with every result field,
// doubles at 17 significant digits (exact), writing any image result as PNG, so the test can
// compare the module's results with the C++ library's bit for bit.
//
//   core_reference --overlay IN OUT
//   core_reference --match A B
//   core_reference --stitch A B OUT
//   core_reference --rotation FX FY CX CY PITCH OUT (YAW IMAGE)...
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "image_converter/feature_matching.h"
#include "image_converter/overlay.h"
#include "image_converter/stitching.h"

namespace {

constexpr const char* kUsage =
    "usage: core_reference --overlay IN OUT\n"
    "       core_reference --match A B\n"
    "       core_reference --stitch A B OUT\n"
    "       core_reference --rotation FX FY CX CY PITCH OUT (YAW IMAGE)...\n\n"
    "Runs image_converter's default overlay, matchPair, stitchPair or stitchByRotation on BGR\n"
    "image files, writes the image result to OUT (PNG) and prints one JSON line with every\n"
    "result field (doubles exact).\n";

void printPair(const image_converter::PairMatch& p) {
  std::printf(R"({"error": "%s", "homography": [)", p.error.c_str());
  for (int k = 0; k < 9; ++k) std::printf("%s%.17g", k ? ", " : "", p.homography(k / 3, k % 3));
  std::printf(
      "], \"keypoints_a\": %d, \"keypoints_b\": %d, \"matches\": %d, \"inliers\": %d, "
      "\"reprojection_error_px\": %.17g, \"refined\": %s, \"held_out_matches\": %d, "
      "\"held_out_median_ransac_px\": %.17g, \"held_out_median_refined_px\": ",
      p.keypoints_a, p.keypoints_b, p.matches, p.inliers, p.reprojection_error_px,
      p.refined ? "true" : "false", p.held_out_matches, p.held_out_median_ransac_px);
  if (p.held_out_median_refined_px) {
    std::printf("%.17g}", *p.held_out_median_refined_px);
  } else {
    std::printf("null}");
  }
}

void printStitch(const image_converter::StitchResult& r) {
  std::printf(R"({"error": "%s", "origin_of_first": [%.17g, %.17g], "pairs": [)", r.error.c_str(),
              r.origin_of_first.x, r.origin_of_first.y);
  for (size_t i = 0; i < r.pairs.size(); ++i) {
    std::printf("%s", i ? ", " : "");
    printPair(r.pairs[i]);
  }
  std::printf("]}\n");
}

cv::Mat read(const char* path) {
  cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
  if (image.empty()) {
    std::cerr << "core_reference: cannot read image '" << path << "'\n";
    std::exit(1);
  }
  return image;
}

int writeOrFail(const char* path, const cv::Mat& image) {
  if (!image.empty() && !cv::imwrite(path, image)) {
    std::cerr << "core_reference: cannot write '" << path << "'\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc >= 2 ? argv[1] : "";
  if (mode == "--help" || mode == "-h") {
    std::cout << kUsage;
    return 0;
  }
  const image_converter::MatchOptions options;
  if (mode == "--overlay" && argc == 4) {
    cv::Mat image = read(argv[2]);
    const bool drawn = image_converter::drawOverlay(image, image_converter::OverlayConfig());
    std::printf("{\"drawn\": %s}\n", drawn ? "true" : "false");
    return writeOrFail(argv[3], image);
  }
  if (mode == "--match" && argc == 4) {
    printPair(image_converter::matchPair(read(argv[2]), read(argv[3]), options));
    std::printf("\n");
    return 0;
  }
  if (mode == "--stitch" && argc == 5) {
    const auto result = image_converter::stitchPair(read(argv[2]), read(argv[3]), options);
    printStitch(result);
    return writeOrFail(argv[4], result.panorama);
  }
  if (mode == "--rotation" && argc >= 10 && (argc - 8) % 2 == 0) {
    image_converter::TurningCamera camera;
    camera.fx = std::stod(argv[2]);
    camera.fy = std::stod(argv[3]);
    camera.cx = std::stod(argv[4]);
    camera.cy = std::stod(argv[5]);
    camera.pitch = std::stod(argv[6]);
    std::vector<double> yaws;
    std::vector<cv::Mat> images;
    for (int i = 8; i < argc; i += 2) {
      yaws.push_back(std::stod(argv[i]));
      images.push_back(read(argv[i + 1]));
    }
    const auto result = image_converter::stitchByRotation(images, yaws, camera);
    printStitch(result);
    return writeOrFail(argv[7], result.panorama);
  }
  std::cerr << "core_reference: bad arguments\n" << kUsage;
  return 2;
}
