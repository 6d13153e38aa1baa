// `rosrun image_converter stitch A.png B.png [C.png ...] -o pano.png [--detector orb|sift]
// [--json]`: stitches overlapping images (left to right) into one panorama. Two images are
// joined by their homography with a feathered seam, more through cv::Stitcher. With --json,
// prints each consecutive pair's homography (row-major 3x3, mapping the second image into the
// first one's pixel frame), match and inlier counts and RMS reprojection error.
// Exit status: 0 done, 1 the images could not be stitched or written, 2 bad command line.
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "image_converter/stitching.h"

namespace {

constexpr const char* kUsage =
    "usage: stitch A.png B.png [C.png ...] -o pano.png [--detector orb|sift] [--json]\n";

struct Arguments {
  std::vector<std::string> inputs;
  std::string output;
  image_converter::MatchOptions options;
  bool json = false;
};

// Fills `arguments`; returns an error message, or "" when the command line is usable.
std::string parse(int argc, char** argv, Arguments& arguments) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "-o" || arg == "--output") {
      if (++i == argc) return arg + " needs a file name";
      arguments.output = argv[i];
    } else if (arg == "--detector") {
      if (++i == argc) return "--detector needs orb or sift";
      if (!image_converter::parseDetector(argv[i], arguments.options.detector)) {
        return std::string("unknown detector '") + argv[i] + "' (use orb or sift)";
      }
    } else if (arg == "--json") {
      arguments.json = true;
    } else if (arg.size() > 1 && arg[0] == '-') {
      return "unknown option " + arg;
    } else {
      arguments.inputs.push_back(arg);
    }
  }
  if (arguments.output.empty()) return "no output file (-o pano.png)";
  if (arguments.inputs.size() < 2) {
    return "need at least two input images, got " + std::to_string(arguments.inputs.size());
  }
  return "";
}

std::string jsonString(const std::string& text) {
  std::ostringstream out;
  out << '"';
  for (const unsigned char c : text) {
    if (c == '"' || c == '\\') {
      out << '\\' << c;
    } else if (c < 0x20) {
      out << "\\u" << std::hex << std::setw(4) << std::setfill('0') << static_cast<int>(c)
          << std::dec;
    } else {
      out << c;
    }
  }
  out << '"';
  return out.str();
}

void printJson(const Arguments& arguments, const image_converter::StitchResult& result,
               const std::string& method) {
  std::ostringstream out;
  out << std::setprecision(10);
  out << "{\n  \"panorama\": " << jsonString(arguments.output)
      << ",\n  \"width\": " << result.panorama.cols << ",\n  \"height\": " << result.panorama.rows
      << ",\n  \"detector\": "
      << jsonString(image_converter::detectorName(arguments.options.detector))
      << ",\n  \"method\": " << jsonString(method) << ",\n  \"pairs\": [";
  for (std::size_t i = 0; i < result.pairs.size(); ++i) {
    const image_converter::PairMatch& pair = result.pairs[i];
    out << (i ? "," : "") << "\n    {\"a\": " << jsonString(arguments.inputs[i])
        << ", \"b\": " << jsonString(arguments.inputs[i + 1]) << ", \"homography\": [";
    for (int k = 0; k < 9; ++k) out << (k ? ", " : "") << pair.homography(k / 3, k % 3);
    out << "], \"matches\": " << pair.matches << ", \"inliers\": " << pair.inliers
        << ", \"reprojection_error_px\": " << pair.reprojection_error_px << "}";
  }
  out << "\n  ]\n}\n";
  std::cout << out.str();
}

}  // namespace

int main(int argc, char** argv) {
  Arguments arguments;
  const std::string usage_error = parse(argc, argv, arguments);
  if (!usage_error.empty()) {
    std::cerr << "stitch: " << usage_error << "\n" << kUsage;
    return 2;
  }
  std::vector<cv::Mat> images;
  for (const std::string& path : arguments.inputs) {
    images.push_back(cv::imread(path, cv::IMREAD_COLOR));
    if (images.back().empty()) {
      std::cerr << "stitch: cannot read image " << path << "\n";
      return 1;
    }
  }
  const bool two = images.size() == 2;
  const image_converter::StitchResult result =
      two ? image_converter::stitchPair(images[0], images[1], arguments.options)
          : image_converter::stitchMany(images, arguments.options);
  if (!result.ok()) {
    std::cerr << "stitch: cannot stitch: " << result.error << "\n";
    return 1;
  }
  bool written = false;
  try {
    written = cv::imwrite(arguments.output, result.panorama);
  } catch (const cv::Exception& error) {
    std::cerr << "stitch: " << error.what() << "\n";
  }
  if (!written) {
    std::cerr << "stitch: cannot write " << arguments.output << "\n";
    return 1;
  }
  if (arguments.json) printJson(arguments, result, two ? "homography" : "cv::Stitcher");
  return 0;
}
