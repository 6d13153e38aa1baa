#include "follow_bot/hsv_box.h"

#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace follow_bot {
namespace {

// A BGR pixel with max channel 255, the given chroma and the given shifted hue numerator
// (see HsvBox), built so HsvBox::contains computes exactly these two values for it.
cv::Vec3b pixelWithHueNumerator(int chroma, int shifted_numerator) {
  const int n =
      shifted_numerator >= 5 * chroma ? shifted_numerator - 6 * chroma : shifted_numerator;
  const int max = 255;
  const int min = max - chroma;
  int b, g, r;
  if (n <= chroma) {  // red sector: n = g - b
    r = max;
    g = n >= 0 ? min + n : min;
    b = n >= 0 ? min : min - n;
  } else if (n <= 3 * chroma) {  // green sector: n - 2 chroma = b - r
    g = max;
    const int m = n - 2 * chroma;
    b = m >= 0 ? min + m : min;
    r = m >= 0 ? min : min - m;
  } else {  // blue sector: n - 4 chroma = r - g
    b = max;
    const int m = n - 4 * chroma;
    r = m >= 0 ? min + m : min;
    g = m >= 0 ? min : min - m;
  }
  return cv::Vec3b(static_cast<uchar>(b), static_cast<uchar>(g), static_cast<uchar>(r));
}

}  // namespace

HsvBox::HsvBox(const HsvColor& lower, const HsvColor& upper) {
  // Appends x, visited in increasing order, to runs[0..max_runs): extends the last run when x
  // follows it, otherwise opens a new run.
  auto add_to_runs = [](Window* runs, int max_runs, int& runs_used, int x) {
    Window* last = runs_used > 0 ? &runs[runs_used - 1] : nullptr;
    if (last != nullptr && x == last->first + static_cast<int>(last->span) + 1) {
      ++last->span;
      return;
    }
    if (runs_used == max_runs) {
      throw std::runtime_error(
          "HsvBox: this OpenCV's BGR->HSV conversion is not monotone as assumed, so no exact "
          "classifier can be built");
    }
    runs[runs_used++] = Window{x, 0};
  };

  // S and V: one pixel per (max, chroma), max = row, chroma = column.
  cv::Mat value_chroma_pixels(256, 256, CV_8UC3, cv::Scalar::all(0));
  for (int max = 0; max < 256; ++max) {
    for (int chroma = 0; chroma <= max; ++chroma) {
      const auto min = static_cast<uchar>(max - chroma);
      value_chroma_pixels.at<cv::Vec3b>(max, chroma) = cv::Vec3b(min, min, static_cast<uchar>(max));
    }
  }
  cv::Mat hsv;
  cv::cvtColor(value_chroma_pixels, hsv, cv::COLOR_BGR2HSV);
  for (int max = 0; max < 256; ++max) {
    int runs_used = 0;
    for (int chroma = 0; chroma <= max; ++chroma) {
      const cv::Vec3b& pixel = hsv.at<cv::Vec3b>(max, chroma);
      if (lower.s <= pixel[1] && pixel[1] <= upper.s && lower.v <= pixel[2] &&
          pixel[2] <= upper.v) {
        add_to_runs(&chroma_by_value_[max], 1, runs_used, chroma);
      }
    }
  }
  // The screen's bounds are the extremes of the exact windows, so it never rejects a member.
  for (int max = 0; max < 256; ++max) {
    const Window& window = chroma_by_value_[max];
    if (window.empty()) continue;
    screen_.min_value = std::min(screen_.min_value, max);
    screen_.max_value = std::max(screen_.max_value, max);
    if (max == 0) continue;  // chroma 0: both saturation products are 0
    screen_.min_saturation = std::min(screen_.min_saturation, 255 * window.first / max);
    screen_.max_saturation =
        std::max(screen_.max_saturation, (255 * window.last() + max - 1) / max);
  }

  // H: one pixel per (chroma, shifted numerator in [0, 6 chroma)), chroma = row. Grey
  // (chroma 0) has the single numerator 0.
  cv::Mat hue_pixels(256, 6 * 255, CV_8UC3, cv::Scalar::all(0));
  for (int chroma = 0; chroma < 256; ++chroma) {
    for (int n = 0; n < std::max(1, 6 * chroma); ++n) {
      hue_pixels.at<cv::Vec3b>(chroma, n) = pixelWithHueNumerator(chroma, n);
    }
  }
  cv::cvtColor(hue_pixels, hsv, cv::COLOR_BGR2HSV);
  for (int chroma = 0; chroma < 256; ++chroma) {
    int runs_used = 0;
    for (int n = 0; n < std::max(1, 6 * chroma); ++n) {
      const int hue = hsv.at<cv::Vec3b>(chroma, n)[0];
      if (lower.h <= hue && hue <= upper.h) {
        add_to_runs(hue_numerator_by_chroma_[chroma].data(), 2, runs_used, n);
      }
    }
  }
}

}  // namespace follow_bot
