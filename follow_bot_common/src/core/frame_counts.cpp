#include "follow_bot_common/frame_counts.h"

namespace follow_bot_common {

namespace {
// The diagnostics key of each FrameOutcome, in the enum's order.
constexpr std::array<const char*, 6> kFrameKeys = {"frames_accepted",       "dropped_bad_encoding",
                                                   "dropped_bad_size",      "dropped_bad_stamp",
                                                   "dropped_size_mismatch", "dropped_error"};
}  // namespace

void FrameCounts::countFrame(FrameOutcome outcome) { ++frames_.at(static_cast<size_t>(outcome)); }

void FrameCounts::countCameraInfo(bool usable) {
  ++(usable ? camera_info_accepted_ : camera_info_dropped_);
}

long FrameCounts::framesDropped() const {
  long dropped = 0;
  for (size_t i = 0; i < frames_.size(); ++i) {
    if (i != static_cast<size_t>(FrameOutcome::kAccepted)) dropped += frames_[i];
  }
  return dropped;
}

std::vector<std::pair<std::string, long>> FrameCounts::frameValues() const {
  std::vector<std::pair<std::string, long>> values;
  for (size_t i = 0; i < frames_.size(); ++i) values.emplace_back(kFrameKeys[i], frames_[i]);
  return values;
}

std::vector<std::pair<std::string, long>> FrameCounts::cameraInfoValues() const {
  return {{"camera_info_accepted", camera_info_accepted_},
          {"dropped_bad_camera_info", camera_info_dropped_}};
}

}  // namespace follow_bot_common
