// Test tool: the parker's TagDetector on image files, for the pose-accuracy test on frames the
// harness renders (tests/test_tag_pose_accuracy.py). Frames are read in the order given, by one
// detector, so the ambiguity tie-break sees them as a sequence.
//
//   tag_pose_probe FX FY CX CY TAG_SIZE IMAGE...
// prints one line per image: "tx ty tz r00 r01 r02 r10 r11 r12 r20 r21 r22 rms_px" (marker in
// the optical frame) or "none".
#include <cstdio>
#include <cstdlib>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "follow_bot/tag_detector.h"

int main(int argc, char** argv) {
  if (argc < 7) {
    std::fprintf(stderr, "usage: %s FX FY CX CY TAG_SIZE IMAGE...\n", argv[0]);
    return 2;
  }
  follow_bot::CameraGeometry camera;
  camera.fx = std::atof(argv[1]);
  camera.fy = std::atof(argv[2]);
  camera.cx = std::atof(argv[3]);
  camera.cy = std::atof(argv[4]);
  follow_bot::TagDetectorConfig config;
  config.size_m = std::atof(argv[5]);
  follow_bot::TagDetector detector(config);
  for (int i = 6; i < argc; ++i) {
    const cv::Mat gray = cv::imread(argv[i], cv::IMREAD_GRAYSCALE);
    const std::optional<follow_bot::MarkerObservation> seen = detector.detect(gray, camera);
    if (!seen) {
      std::printf("none\n");
      continue;
    }
    const cv::Vec3d& t = seen->translation;
    const cv::Matx33d& r = seen->rotation;
    std::printf("%.9f %.9f %.9f", t[0], t[1], t[2]);
    for (int k = 0; k < 9; ++k) std::printf(" %.9f", r.val[k]);
    std::printf(" %.6f\n", seen->reprojection_error_px);
  }
  return 0;
}
