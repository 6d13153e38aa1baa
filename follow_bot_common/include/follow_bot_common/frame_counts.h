// What a node did with every camera frame and camera_info it received, for /diagnostics: each
// message counted once, under its outcome, so that the counts add up to what arrived and a test
// can hold them against what it sent.
#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "follow_bot_common/image_frame.h"

namespace follow_bot_common {

class FrameCounts {
 public:
  void countFrame(FrameOutcome outcome);
  // A camera_info taken as the lens' intrinsics (`usable`) or ignored.
  void countCameraInfo(bool usable);
  long framesDropped() const;
  // "frames_accepted", then "dropped_<reason>" for every FrameOutcome, zeros included.
  std::vector<std::pair<std::string, long>> frameValues() const;
  // "camera_info_accepted", "dropped_bad_camera_info".
  std::vector<std::pair<std::string, long>> cameraInfoValues() const;

 private:
  std::array<long, 6> frames_{};  // by FrameOutcome
  long camera_info_accepted_ = 0;
  long camera_info_dropped_ = 0;
};

}  // namespace follow_bot_common
