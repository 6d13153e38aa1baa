// `rosrun image_converter stitch A.png B.png [C.png ...] -o pano.png [--detector orb|sift|akaze]
// [--json] [--verbose]`: stitches overlapping images (left to right) into one panorama. Two
// images are joined by their homography with a feathered seam, more through cv::Stitcher. With
// --json, prints each consecutive pair's homography (row-major 3x3, mapping the second image
// into the first one's pixel frame), match and inlier counts, RMS reprojection error and whether
// the ECC refinement was kept; --verbose says the latter per pair on stderr.
// Exit status: 0 done, 1 the images could not be stitched or written, 2 bad command line.
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <boost/program_options.hpp>
#include <opencv2/imgcodecs.hpp>

#include "image_converter/stitching.h"

namespace {

constexpr const char* kUsage =
    "usage: stitch A.png B.png [C.png ...] -o pano.png [--detector orb|sift|akaze] [--json]\n"
    "              [--verbose]\n\n"
    "Stitches overlapping images (left to right) into one panorama";

struct Arguments {
  std::vector<std::string> inputs;
  std::string output;
  image_converter::MatchOptions options;
  bool json = false;
  bool verbose = false;
  bool help = false;
};

namespace po = boost::program_options;

// Fills `arguments`; returns an error message, or "" when the command line is usable (or asks
// for --help). `usage` gets the usage text with every option.
std::string parse(int argc, char** argv, Arguments& arguments, std::string& usage) {
  po::options_description options(kUsage);
  std::string detector = image_converter::detectorName(arguments.options.detector);
  options.add_options()("help,h", po::bool_switch(&arguments.help), "print this help and exit")(
      "output,o", po::value(&arguments.output)->value_name("FILE"), "panorama to write")(
      "detector", po::value(&detector)->value_name("orb|sift|akaze")->default_value(detector),
      "feature detector")("json", po::bool_switch(&arguments.json),
                          "print each pair's homography, match and inlier counts, RMS "
                          "reprojection error and ECC verdict as JSON")(
      "verbose,v", po::bool_switch(&arguments.verbose),
      "say on stderr, for each pair, whether the ECC refinement was kept and the held-out errors "
      "that decided it");
  std::ostringstream text;
  text << options;
  usage = text.str();
  po::options_description all;
  all.add(options).add_options()("inputs", po::value(&arguments.inputs));
  po::positional_options_description positional;
  positional.add("inputs", -1);
  try {
    po::variables_map values;
    po::store(po::command_line_parser(argc, argv).options(all).positional(positional).run(),
              values);
    po::notify(values);
  } catch (const po::error& error) {
    return error.what();
  }
  if (arguments.help) return "";
  const auto parsed = image_converter::parseDetector(detector);
  if (!parsed) return "unknown detector '" + detector + "' (use orb, sift or akaze)";
  arguments.options.detector = *parsed;
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
        << ", \"reprojection_error_px\": " << pair.reprojection_error_px
        << ", \"refined\": " << (pair.refined ? "true" : "false")
        << ", \"held_out_matches\": " << pair.held_out_matches
        << ", \"held_out_median_ransac_px\": " << pair.held_out_median_ransac_px
        << ", \"held_out_median_refined_px\": ";
    if (pair.held_out_median_refined_px) {
      out << *pair.held_out_median_refined_px;
    } else {
      out << "null";
    }
    out << "}";
  }
  out << "\n  ]\n}\n";
  std::cout << out.str();
}

// One line per pair: which homography was kept and the held-out medians that decided it.
void printVerdicts(const Arguments& arguments, const image_converter::StitchResult& result) {
  for (std::size_t i = 0; i < result.pairs.size(); ++i) {
    const image_converter::PairMatch& pair = result.pairs[i];
    std::ostringstream line;
    line << std::fixed << std::setprecision(3) << "stitch: " << arguments.inputs[i] << " + "
         << arguments.inputs[i + 1] << ": " << pair.inliers << " inliers of " << pair.matches
         << " matches; ";
    if (pair.held_out_matches == 0) {
      line << "ECC refinement not tried (too few inliers to hold some out)";
    } else if (!pair.held_out_median_refined_px) {
      line << "ECC refinement failed, RANSAC kept";
    } else {
      line << (pair.refined ? "ECC refinement kept" : "RANSAC kept, ECC refinement rejected")
           << ": held-out median error " << *pair.held_out_median_refined_px << " px refined, "
           << pair.held_out_median_ransac_px << " px RANSAC (" << pair.held_out_matches
           << " held-out matches)";
    }
    std::cerr << line.str() << "\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  Arguments arguments;
  std::string usage;
  const std::string usage_error = parse(argc, argv, arguments, usage);
  if (!usage_error.empty()) {
    std::cerr << "stitch: " << usage_error << "\n" << usage;
    return 2;
  }
  if (arguments.help) {
    std::cout << usage;
    return 0;
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
  if (arguments.verbose) printVerdicts(arguments, result);
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
