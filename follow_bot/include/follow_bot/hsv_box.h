// Exact, fast classification of BGR pixels by an OpenCV HSV box (the line detector's colour
// test).
#pragma once

#include <algorithm>
#include <array>

namespace follow_bot {

// A colour in OpenCV's 8-bit HSV: H in 0..179 (degrees / 2), S and V in 0..255.
struct HsvColor {
  int h = 0;
  int s = 0;
  int v = 0;
};

// Exact, fast membership test for an HSV box: contains(b, g, r) is true exactly when
// cv::inRange(cv::cvtColor(pixel, COLOR_BGR2HSV), lower, upper) would be 255.
//
// How: with max = max(b, g, r) and chroma = max - min(b, g, r), OpenCV's V is max, its S depends
// only on (max, chroma) and rises with chroma, and its H depends only on (chroma, n) where n is
// the hue numerator of the max channel's sector (g - b, b - r + 2 chroma or r - g + 4 chroma,
// plus 6 chroma when negative). H rises with n from 0 to 179 except for a short tail that
// rounds to 180 and wraps to 0, so any H interval is at most two runs of n. The box is thus
// "chroma in a window chosen by max" and "n in one of two windows chosen by chroma". The
// window tables are filled at construction by running cv::cvtColor itself over every
// (max, chroma) and every (chroma, n), so they agree with the linked OpenCV by construction;
// the constructor throws std::runtime_error if that OpenCV breaks the run structure, and the
// unit tests check the equivalence over all 2^24 colours.
class HsvBox {
 public:
  // Inclusive bounds, as for cv::inRange. An empty box (some lower > upper) matches nothing.
  HsvBox(const HsvColor& lower, const HsvColor& upper);

  bool contains(int b, int g, int r) const {
    const int max = std::max(std::max(b, g), r);
    const int chroma = max - std::min(std::min(b, g), r);
    // OpenCV's sector rule: red is the max channel on ties, then green.
    int n = max == r ? g - b : max == g ? b - r + 2 * chroma : r - g + 4 * chroma;
    n += n < 0 ? 6 * chroma : 0;
    return containsDecomposed(max, chroma, n);
  }

  // contains() for a pixel already reduced to its max channel, chroma and shifted hue
  // numerator n (all as above), for callers that compute those in bulk.
  bool containsDecomposed(int max, int chroma, int n) const {
    const std::array<Window, 2>& hue_windows = hue_numerator_by_chroma_[chroma];
    // Bitwise & and | (on ints, as bools would invite && and ||) keep this branch-free:
    // callers feed it pixels near the box edges.
    const int value_in = chroma_by_value_[max].contains(chroma);
    const int hue_in = static_cast<int>(hue_windows[0].contains(n)) | hue_windows[1].contains(n);
    return (value_in & hue_in) != 0;
  }

  // A cheap necessary condition for contains(), for vectorised pre-screening: every pixel in
  // the box has min_value <= max <= max_value and
  // min_saturation * max <= 255 * chroma <= max_saturation * max (all products fit 16 bits).
  struct Screen {
    int min_value = 255;
    int max_value = 0;
    int min_saturation = 255;
    int max_saturation = 0;
  };
  const Screen& screen() const { return screen_; }

 private:
  // An inclusive integer range [first, first + span]; the default one is empty.
  struct Window {
    int first = 1 << 20;  // beyond every value looked up, so x - first < 0
    unsigned span = 0;
    bool empty() const { return first == Window().first; }
    int last() const { return first + static_cast<int>(span); }
    // One unsigned comparison: x below first wraps to a huge value.
    bool contains(int x) const { return static_cast<unsigned>(x - first) <= span; }
  };

  std::array<Window, 256> chroma_by_value_;
  std::array<std::array<Window, 2>, 256> hue_numerator_by_chroma_;
  Screen screen_;
};

}  // namespace follow_bot
