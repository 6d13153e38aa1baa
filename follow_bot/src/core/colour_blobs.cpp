#include "follow_bot/colour_blobs.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "follow_bot/common.h"
#include "follow_bot_common/config_checks.h"

namespace follow_bot {
namespace {

// The contour's smallest enclosing circle, from its few hull vertices: the same circle, where
// minEnclosingCircle of a box's whole outline (long straight runs of boundary pixels) takes
// milliseconds.
cv::Vec3f enclosingCircle(const std::vector<cv::Point>& contour) {
  std::vector<cv::Point> hull;
  cv::convexHull(contour, hull);
  cv::Point2f centre;
  float radius = 0.0f;
  cv::minEnclosingCircle(hull, centre, radius);
  return {centre.x, centre.y, radius};
}

constexpr int kHueCount = 180;  // OpenCV 8-bit hue: 0..179

std::string checkKernel(const char* name, int size) {
  if (size >= 0 && (size <= 1 || size % 2 == 1)) return "";
  std::ostringstream message;
  message << name << " must be 0 (off) or an odd size, got " << size;
  return message.str();
}

std::string checkSpec(const ColourSpec& spec) {
  if (spec.name.empty()) return "name must not be empty";
  for (const std::string& error : {
           requireInRange("hue_centre", spec.hue_centre, 0, kHueCount - 1),
           requireInRange("sensitivity", spec.sensitivity, 0, 90),
           requireInRange("s_min", spec.s_min, 0, 255),
           requireInRange("v_min", spec.v_min, 0, 255),
           requireInRange("median_hue_min", spec.median_hue_min, -90, spec.median_hue_max),
           requireInRange("median_hue_max", spec.median_hue_max, spec.median_hue_min, 90),
           requireInRange("hue_offset_max", spec.hue_offset_max, 0, 90),
       }) {
    if (!error.empty()) return error;
  }
  return "";
}

cv::Mat ellipseKernel(int size) {
  if (size <= 1) return cv::Mat();
  return cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(size, size));
}

// Boundary pixels within this of a ball's circle, plus the roundness tolerance's fraction of its
// radius, lie on it (pixel quantisation).
constexpr double kQuantisationPx = 1.0;
// RANSAC draws: with half the boundary on the ball, 100 draws all miss it with p ~ 2e-6.
constexpr int kRansacDraws = 100;
// A shape-judged contour is scored on at most this many of its pixels (evenly spread).
constexpr std::size_t kMaxScoredPixels = 200;
// A RANSAC circle is a ball's when its in-band boundary pixels trace this share of its arc inside
// the frame (36 bins of 10 degrees; a ball with its shadow or 40 % hidden keeps ~0.6-0.75, the
// circle inscribed in a square touches ~0.45), the blob fills this share of the circle (within
// the frame; a blue sweet's specular spot leaves 0.49).
constexpr int kArcBins = 36;
constexpr double kMinArcCoverage = 0.6;
constexpr int kMinArcBins = kArcBins / 3;
constexpr int kMinVisibleBins = kArcBins * 2 / 3;
constexpr double kMinCircleFill = 0.4;
// Touching balls of one colour (or a red and an orange sweet in red's hue window) make one blob.
constexpr int kMaxBallsPerBlob = 4;
// A blob is split by saturation when its two Otsu classes' mean saturations are this far apart:
// the harsh sweep's reddish wood reads S ~116, the red ball on it 255.
constexpr double kMinSaturationGap = 60.0;

bool interior(const cv::Point2d& p, cv::Size image) {
  return p.x > 0 && p.y > 0 && p.x < image.width - 1 && p.y < image.height - 1;
}

std::vector<cv::Point2d> interiorPixels(const std::vector<cv::Point>& contour, cv::Size image) {
  std::vector<cv::Point2d> arc;
  for (const cv::Point& p : contour) {
    if (interior(p, image)) arc.push_back(p);
  }
  return arc;
}

// The least-squares circle (Kasa) through `arc`: x^2 + y^2 + D x + E y + F = 0, linear in
// (D, E, F); rms_error over all of `arc`.
std::optional<CircleFit> kasaFit(const std::vector<cv::Point2d>& arc) {
  constexpr std::size_t kMinPoints = 5;
  if (arc.size() < kMinPoints) return std::nullopt;
  cv::Mat a(static_cast<int>(arc.size()), 3, CV_64F);
  cv::Mat b(static_cast<int>(arc.size()), 1, CV_64F);
  for (int i = 0; i < a.rows; ++i) {
    const cv::Point2d& p = arc[i];
    a.at<double>(i, 0) = p.x;
    a.at<double>(i, 1) = p.y;
    a.at<double>(i, 2) = 1.0;
    b.at<double>(i) = -(p.x * p.x + p.y * p.y);
  }
  const cv::SVD svd(a);
  // Rank < 3: the pixels lie on one line, which fits no circle.
  if (svd.w.at<double>(2) <= 1e-9 * svd.w.at<double>(0)) return std::nullopt;
  cv::Mat def;
  svd.backSubst(b, def);
  CircleFit fit;
  fit.centre = {-def.at<double>(0) / 2.0, -def.at<double>(1) / 2.0};
  const double radius_squared = fit.centre.dot(fit.centre) - def.at<double>(2);
  if (!(radius_squared > 0.0) || !std::isfinite(radius_squared)) return std::nullopt;
  fit.radius = std::sqrt(radius_squared);
  double sum_squared = 0.0;
  for (const cv::Point2d& p : arc) {
    const double error = cv::norm(p - fit.centre) - fit.radius;
    sum_squared += error * error;
  }
  fit.rms_error = std::sqrt(sum_squared / static_cast<double>(arc.size()));
  return fit;
}

double band(double radius, double tolerance) { return kQuantisationPx + tolerance * radius; }

std::vector<cv::Point2d> inliersOf(const std::vector<cv::Point2d>& arc, const CircleFit& circle,
                                   double tolerance) {
  const double limit = band(circle.radius, tolerance);
  std::vector<cv::Point2d> inliers;
  for (const cv::Point2d& p : arc) {
    if (std::abs(cv::norm(p - circle.centre) - circle.radius) <= limit) inliers.push_back(p);
  }
  return inliers;
}

// The circle through three points; nullopt when they are (nearly) collinear.
std::optional<CircleFit> circleThrough(const cv::Point2d& a, const cv::Point2d& b,
                                       const cv::Point2d& c) {
  const cv::Point2d ab = b - a, ac = c - a;
  const double d = 2.0 * ab.cross(ac);
  if (std::abs(d) < 1e-6) return std::nullopt;
  const double ab2 = ab.dot(ab), ac2 = ac.dot(ac);
  const cv::Point2d offset((ac.y * ab2 - ab.y * ac2) / d, (ab.x * ac2 - ac.x * ab2) / d);
  CircleFit circle;
  circle.centre = a + offset;
  circle.radius = cv::norm(offset);
  return circle;
}

// The circle of at least `min_radius` that the most of `arc` lies on within the band, per px of
// band (the band widens with the radius, which would favour large circles through two blobs):
// RANSAC over triples of its pixels (a fixed seed: the same frame gives the same answer), then
// least squares on the inliers, twice.
std::optional<CircleFit> ransacCircle(const std::vector<cv::Point2d>& arc, double tolerance,
                                      double min_radius, cv::Size image) {
  constexpr std::size_t kMinPoints = 5;
  if (arc.size() < kMinPoints) return std::nullopt;
  std::vector<cv::Point2d> scored;
  const std::size_t stride = (arc.size() + kMaxScoredPixels - 1) / kMaxScoredPixels;
  for (std::size_t i = 0; i < arc.size(); i += stride) scored.push_back(arc[i]);
  const double max_radius = std::hypot(image.width, image.height);
  cv::RNG random(0x5eed);
  std::optional<CircleFit> best;
  double best_score = 0.0;
  const int n = static_cast<int>(scored.size());
  for (int draw = 0; draw < kRansacDraws; ++draw) {
    const std::optional<CircleFit> circle = circleThrough(
        scored[random.uniform(0, n)], scored[random.uniform(0, n)], scored[random.uniform(0, n)]);
    if (!circle || circle->radius < min_radius || circle->radius > max_radius) continue;
    const double score = static_cast<double>(inliersOf(scored, *circle, tolerance).size()) /
                         band(circle->radius, tolerance);
    if (score > best_score) {
      best_score = score;
      best = circle;
    }
  }
  for (int refit = 0; best && refit < 2; ++refit) best = kasaFit(inliersOf(arc, *best, tolerance));
  return best;
}

// The share of `circle`'s arc inside the frame that `traced` pixels lie along; 0 when they trace
// less than kMinArcBins or the frame holds less than kMinVisibleBins of it.
double arcCoverage(const CircleFit& circle, const std::vector<cv::Point2d>& traced,
                   cv::Size image) {
  std::array<bool, kArcBins> hit{};
  for (const cv::Point2d& p : traced) {
    const double angle = std::atan2(p.y - circle.centre.y, p.x - circle.centre.x) + CV_PI;
    hit[std::min(kArcBins - 1, static_cast<int>(angle / (2.0 * CV_PI) * kArcBins))] = true;
  }
  int visible = 0, covered = 0;
  for (int bin = 0; bin < kArcBins; ++bin) {
    const double angle = (bin + 0.5) * 2.0 * CV_PI / kArcBins - CV_PI;
    const cv::Point2d p =
        circle.centre + circle.radius * cv::Point2d(std::cos(angle), std::sin(angle));
    if (!interior(p, image)) continue;
    ++visible;
    covered += hit[bin];
  }
  // A circle the frame's edge cuts much of is not judged from part of its arc (a box's corner
  // at the edge traces one as well as a ball's outline does).
  if (visible < kMinVisibleBins) return 0.0;
  // A short arc (a box's corner cut by the frame's edge) establishes no ball.
  if (covered < kMinArcBins) return 0.0;
  return static_cast<double>(covered) / visible;
}

void drawDisk(cv::Mat& mask, const cv::Point2d& centre, double radius) {
  constexpr int kShift = 4;  // sub-pixel centre and radius
  constexpr double kScale = 1 << kShift;
  cv::circle(mask, cv::Point(cvRound(centre.x * kScale), cvRound(centre.y * kScale)),
             cvRound(radius * kScale), 255, cv::FILLED, cv::LINE_8, kShift);
}

// The median of the hues of `hsv`'s pixels under `mask`, as an offset from `centre` in -90..89.
int medianHueOffset(const cv::Mat& hsv, const cv::Mat& mask, int centre) {
  std::array<int, kHueCount> counts{};
  int total = 0;
  for (int r = 0; r < mask.rows; ++r) {
    const uchar* inside = mask.ptr<uchar>(r);
    const cv::Vec3b* pixel = hsv.ptr<cv::Vec3b>(r);
    for (int c = 0; c < mask.cols; ++c) {
      if (!inside[c]) continue;
      ++counts[(pixel[c][0] - centre + kHueCount + kHueCount / 2) % kHueCount];
      ++total;
    }
  }
  int seen = 0;
  for (int offset = 0; offset < kHueCount; ++offset) {
    seen += counts[offset];
    if (2 * seen >= total) return offset - kHueCount / 2;
  }
  return 0;
}

}  // namespace

// A blob the gates let through: its pixels' outline and the circle it is ranked by.
struct ColourBlobDetector::Candidate {
  std::vector<cv::Point> contour;
  cv::Vec3f circle;   // x, y, radius
  double rank = 0.0;  // larger: nearer (a ball's radius) or larger (any shape: its area)
};

std::optional<ColourSpec> parseColourName(const std::string& name) {
  ColourSpec spec;
  spec.name = name;
  if (name == "red") {
    spec.hue_centre = 0;
    // Smarties: red sweets' median hue is 0, orange ones' 6..9, a brown one's -6 (174); the
    // harness's orange clutter 16, its pink clutter -15 (165: a pink box stopped the harsh
    // follow-green sweep's member 005 for 9 s).
    spec.median_hue_min = -8;
    spec.median_hue_max = 3;
    // Smarties: 99 % of a red sweet's pixels lie in -8..4; what an orange sweet keeps below 10
    // still has a median of 6 or more.
    spec.hue_offset_max = 10;
  } else if (name == "green") {
    spec.hue_centre = 60;
  } else if (name == "blue") {
    spec.hue_centre = 120;
  } else {
    return std::nullopt;
  }
  return spec;
}

std::string colourSpecsFromNames(const std::vector<std::string>& names,
                                 std::vector<ColourSpec>& specs) {
  std::vector<ColourSpec> parsed;
  for (const std::string& name : names) {
    const std::optional<ColourSpec> spec = parseColourName(name);
    if (!spec) return "unknown colour name '" + name + "' (known: red, green, blue)";
    parsed.push_back(*spec);
  }
  specs = parsed;
  return "";
}

std::string validate(const ColourBlobConfig& config) {
  if (config.colours.empty()) return "colours must name at least one colour";
  std::set<std::string> names;
  for (size_t i = 0; i < config.colours.size(); ++i) {
    const ColourSpec& spec = config.colours[i];
    std::string error = checkSpec(spec);
    if (error.empty() && !names.insert(spec.name).second) error = "name is a duplicate";
    if (!error.empty()) {
      std::ostringstream message;
      message << "colours[" << i << "] (" << spec.name << "): " << error;
      return message.str();
    }
  }
  for (const std::string& error : {
           checkKernel("open_kernel", config.open_kernel),
           checkKernel("close_kernel", config.close_kernel),
           checkFields(config),
       }) {
    if (!error.empty()) return error;
  }
  if (const auto& ball = config.floor_ball) {
    for (const std::string& error : {
             requirePositive("floor_ball.radius_m", ball->radius_m),
             requireInRange("floor_ball.tolerance", ball->tolerance, 0.0, 1.0),
         }) {
      if (!error.empty()) return error;
    }
    if (const std::string error = validate(ball->camera); !error.empty()) {
      return "floor_ball.camera: " + error;
    }
  }
  return "";
}

std::optional<CircleFit> fitCircle(const std::vector<cv::Point>& contour, cv::Size image) {
  return kasaFit(interiorPixels(contour, image));
}

std::optional<double> floorBallRadius(const CameraGeometry& camera, const cv::Point2d& centre,
                                      double radius_px) {
  if (!(radius_px > 0.0) || !std::isfinite(centre.x) || !std::isfinite(centre.y)) {
    return std::nullopt;
  }
  // The circle's ends on the line from the principal point through its centre (any line when
  // the centre is the principal point), as rays of the rectified camera (x right, y down, z
  // along the optical axis).
  const cv::Point2d principal(camera.cx, camera.cy);
  cv::Point2d along = centre - principal;
  const double offset = cv::norm(along);
  along = offset > 1e-9 ? along / offset : cv::Point2d(0.0, 1.0);
  const auto ray = [&](const cv::Point2d& raw) {
    const cv::Point2d p = rectifyPixel(camera, raw);
    return cv::normalize(
        cv::Vec3d((p.x - camera.cx) / camera.fx, (p.y - camera.cy) / camera.fy, 1.0));
  };
  const cv::Vec3d near = ray(centre - radius_px * along);
  const cv::Vec3d far = ray(centre + radius_px * along);
  const double alpha = 0.5 * std::acos(std::clamp(near.dot(far), -1.0, 1.0));
  const cv::Vec3d axis = cv::normalize(near + far);
  const double sin_theta =
      axis[1] * std::cos(camera.pitch_rad) + axis[2] * std::sin(camera.pitch_rad);
  const double denominator = 1.0 + sin_theta / std::sin(alpha);
  if (!(alpha > 0.0) || !(denominator > 0.0)) return std::nullopt;
  const double radius = camera.height_m / denominator;
  return std::isfinite(radius) ? std::optional<double>(radius) : std::nullopt;
}

const ColourBlob* BlobResult::find(const std::string& name) const {
  for (const ColourBlob& blob : colours) {
    if (blob.name == name) return &blob;
  }
  return nullptr;
}

ColourBlobDetector::ColourBlobDetector(const ColourBlobConfig& config)
    : config_(config),
      open_kernel_(ellipseKernel(config.open_kernel)),
      close_kernel_(ellipseKernel(config.close_kernel)) {
  const std::string error = validate(config);
  if (!error.empty()) throw std::invalid_argument("ColourBlobDetector: " + error);
}

void ColourBlobDetector::cleanedMask(const cv::Mat& hsv, const ColourSpec& spec,
                                     cv::Mat& mask) const {
  // The hue window [centre - s, centre + min(s, hue_offset_max)] on the hue circle is one
  // interval, or two when it crosses 0/179 (red).
  const int low = spec.hue_centre - spec.sensitivity;
  const int high = spec.hue_centre + std::min(spec.sensitivity, spec.hue_offset_max);
  const auto threshold = [&](int hue_low, int hue_high, cv::Mat& out) {
    cv::inRange(hsv, cv::Scalar(hue_low, spec.s_min, spec.v_min), cv::Scalar(hue_high, 255, 255),
                out);
  };
  threshold(std::max(low, 0), std::min(high, kHueCount - 1), mask);
  if (low < 0 || high >= kHueCount) {
    cv::Mat wrapped;
    if (low < 0) {
      threshold(low + kHueCount, kHueCount - 1, wrapped);
    } else {
      threshold(0, high - kHueCount, wrapped);
    }
    cv::bitwise_or(mask, wrapped, mask);
  }
  if (!open_kernel_.empty()) cv::morphologyEx(mask, mask, cv::MORPH_OPEN, open_kernel_);
  if (!close_kernel_.empty()) cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, close_kernel_);
}

BlobResult ColourBlobDetector::detect(const cv::Mat& bgr) const {
  BlobResult result;
  for (const ColourSpec& spec : config_.colours) {
    result.colours.emplace_back();
    result.colours.back().name = spec.name;
  }
  if (bgr.empty()) {
    result.error = "empty frame";
    return result;
  }
  if (bgr.type() != CV_8UC3) {
    result.error = "expected a CV_8UC3 (BGR) frame, got type " + std::to_string(bgr.type());
    return result;
  }
  result.image_width = bgr.cols;
  result.image_height = bgr.rows;

  cv::Mat hsv;
  cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
  cv::Mat mask;
  std::vector<std::vector<cv::Point>> contours;
  for (size_t i = 0; i < config_.colours.size(); ++i) {
    cleanedMask(hsv, config_.colours[i], mask);
    cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);

    ColourBlob& blob = result.colours[i];
    std::vector<Candidate> candidates;
    for (const std::vector<cv::Point>& contour : contours) {
      if (cv::contourArea(contour) < config_.min_area) continue;
      const std::size_t before = candidates.size();
      judge(contour, hsv, config_.colours[i], candidates);
      if (candidates.size() == before) {
        judgeSaturatedPart(contour, mask, hsv, config_.colours[i], candidates);
      }
    }
    if (candidates.empty()) continue;
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const Candidate& a, const Candidate& b) { return a.rank > b.rank; });

    blob.found = true;
    blob.blob_count = static_cast<int>(candidates.size());
    for (const Candidate& candidate : candidates) blob.circles.push_back(candidate.circle);
    blob.contour = std::move(candidates.front().contour);
    blob.area = cv::contourArea(blob.contour);
    const cv::Vec3f circle = enclosingCircle(blob.contour);
    blob.circle_centre = {circle[0], circle[1]};
    blob.circle_radius = circle[2];
    blob.bounding_box = cv::boundingRect(blob.contour);
    const cv::Moments moments = cv::moments(blob.contour);
    // A zero-area contour (a line of pixels, only with min_area 0) has no moment centroid.
    blob.centroid = moments.m00 > 0.0
                        ? cv::Point2d(moments.m10 / moments.m00, moments.m01 / moments.m00)
                        : cv::Point2d(blob.circle_centre);
  }
  return result;
}

bool ColourBlobDetector::acceptable(const std::optional<CircleFit>& ball,
                                    const std::vector<cv::Point>& contour, const cv::Mat& hsv,
                                    const ColourSpec& spec) const {
  if (ball && config_.floor_ball) {
    const ColourBlobConfig::FloorBall& floor = *config_.floor_ball;
    // Boundary pixel centres lie half a pixel inside the silhouette's edge.
    const std::optional<double> radius =
        floorBallRadius(floor.camera, ball->centre, ball->radius + 0.5);
    if (!radius || std::abs(*radius - floor.radius_m) > floor.tolerance * floor.radius_m) {
      return false;
    }
  }
  if (spec.median_hue_min > -kHueCount / 2 || spec.median_hue_max < kHueCount / 2 - 1) {
    const cv::Rect roi = cv::boundingRect(contour);
    cv::Mat pixels = cv::Mat::zeros(roi.size(), CV_8UC1);
    cv::drawContours(pixels, std::vector<std::vector<cv::Point>>{contour}, 0, 255, cv::FILLED,
                     cv::LINE_8, cv::noArray(), INT_MAX, -roi.tl());
    const int median = medianHueOffset(hsv(roi), pixels, spec.hue_centre);
    if (median < spec.median_hue_min || median > spec.median_hue_max) return false;
  }
  return true;
}

void ColourBlobDetector::judge(const std::vector<cv::Point>& contour, const cv::Mat& hsv,
                               const ColourSpec& spec, std::vector<Candidate>& candidates) const {
  const cv::Size image = hsv.size();
  const double tolerance = config_.roundness_tolerance;
  const bool round_gate = tolerance > 0.0;
  const auto add = [&](std::vector<cv::Point> outline, const std::optional<CircleFit>& ball) {
    if (!acceptable(ball, outline, hsv, spec)) return;
    Candidate candidate;
    if (round_gate && ball) {
      candidate.circle = {static_cast<float>(ball->centre.x), static_cast<float>(ball->centre.y),
                          static_cast<float>(ball->radius + 0.5)};
      candidate.rank = ball->radius;
    } else {
      candidate.circle = enclosingCircle(outline);
      const double area = cv::contourArea(outline);
      // Balls whose shape cannot be judged (cut by the frame all round) rank by an equal disk's.
      candidate.rank = round_gate ? std::sqrt(area / CV_PI) : area;
    }
    candidate.contour = std::move(outline);
    candidates.push_back(std::move(candidate));
  };
  if (!round_gate && !config_.floor_ball) return add(contour, std::nullopt);
  std::vector<cv::Point2d> arc = interiorPixels(contour, image);
  const std::optional<CircleFit> whole = kasaFit(arc);
  if (!round_gate || !whole || whole->rms_error <= band(whole->radius, tolerance)) {
    return add(contour, whole);
  }
  // Not round as a whole: a ball with a shadow, a notch or a part hidden, touching balls, or no
  // ball. Each circle RANSAC finds is judged, then its boundary pixels are set aside.
  const cv::Rect contour_box = cv::boundingRect(contour);
  std::vector<CircleFit> balls;
  for (int found = 0; found < kMaxBallsPerBlob; ++found) {
    // A ball smaller than min_area is none.
    const std::optional<CircleFit> ball =
        ransacCircle(arc, tolerance, std::sqrt(config_.min_area / CV_PI), image);
    if (!ball) return;
    std::vector<cv::Point2d> rest;
    const double limit = band(ball->radius, tolerance);
    for (const cv::Point2d& p : arc) {
      if (std::abs(cv::norm(p - ball->centre) - ball->radius) > limit) rest.push_back(p);
    }
    std::vector<cv::Point2d> traced = inliersOf(arc, *ball, tolerance);
    if (arcCoverage(*ball, traced, image) < kMinArcCoverage) return;
    arc = std::move(rest);
    // What is left of a ball's outline beside it fits small circles inside it: no balls.
    const bool inside_another = std::any_of(balls.begin(), balls.end(), [&](const CircleFit& b) {
      return cv::norm(b.centre - ball->centre) < std::max(b.radius, ball->radius);
    });
    balls.push_back(*ball);
    if (inside_another) continue;
    // The blob cut to the circle (widened by the band).
    const double reach = ball->radius + limit;
    const cv::Rect disk_box(
        cv::Point(cvFloor(ball->centre.x - reach), cvFloor(ball->centre.y - reach)),
        cv::Point(cvCeil(ball->centre.x + reach) + 1, cvCeil(ball->centre.y + reach) + 1));
    const cv::Rect roi = (contour_box | disk_box) & cv::Rect(cv::Point(), image);
    cv::Mat pixels = cv::Mat::zeros(roi.size(), CV_8UC1);
    cv::drawContours(pixels, std::vector<std::vector<cv::Point>>{contour}, 0, 255, cv::FILLED,
                     cv::LINE_8, cv::noArray(), INT_MAX, -roi.tl());
    cv::Mat disk = cv::Mat::zeros(roi.size(), CV_8UC1);
    drawDisk(disk, ball->centre - cv::Point2d(roi.tl()), reach);
    const int disk_px = cv::countNonZero(disk);
    cv::bitwise_and(pixels, disk, pixels);
    if (cv::countNonZero(pixels) < kMinCircleFill * disk_px) continue;
    std::vector<std::vector<cv::Point>> parts;
    cv::findContours(pixels, parts, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE, roi.tl());
    if (parts.empty()) continue;
    std::vector<cv::Point>& largest = *std::max_element(
        parts.begin(), parts.end(),
        [](const auto& a, const auto& b) { return cv::contourArea(a) < cv::contourArea(b); });
    if (cv::contourArea(largest) >= config_.min_area) add(std::move(largest), ball);
  }
}

void ColourBlobDetector::judgeSaturatedPart(const std::vector<cv::Point>& contour,
                                            const cv::Mat& mask, const cv::Mat& hsv,
                                            const ColourSpec& spec,
                                            std::vector<Candidate>& candidates) const {
  const cv::Rect roi = cv::boundingRect(contour);
  cv::Mat pixels = cv::Mat::zeros(roi.size(), CV_8UC1);
  cv::drawContours(pixels, std::vector<std::vector<cv::Point>>{contour}, 0, 255, cv::FILLED,
                   cv::LINE_8, cv::noArray(), INT_MAX, -roi.tl());
  cv::bitwise_and(pixels, mask(roi), pixels);
  cv::Mat saturation;
  cv::extractChannel(hsv(roi), saturation, 1);
  std::array<double, 256> counts{};
  double total = 0.0, sum = 0.0;
  for (int r = 0; r < roi.height; ++r) {
    const uchar* in = pixels.ptr<uchar>(r);
    const uchar* s = saturation.ptr<uchar>(r);
    for (int c = 0; c < roi.width; ++c) {
      if (!in[c]) continue;
      ++counts[s[c]];
      ++total;
      sum += s[c];
    }
  }
  // Otsu: the level that maximises the between-class variance, with the classes' means.
  double below = 0.0, below_sum = 0.0, best = 0.0, gap = 0.0;
  int level = -1;
  for (int t = 0; t < 255; ++t) {
    below += counts[t];
    below_sum += t * counts[t];
    const double above = total - below;
    if (below == 0.0 || above == 0.0) continue;
    const double low_mean = below_sum / below, high_mean = (sum - below_sum) / above;
    const double between = below * above * (high_mean - low_mean) * (high_mean - low_mean);
    if (between > best) {
      best = between;
      level = t;
      gap = high_mean - low_mean;
    }
  }
  if (level < 0 || gap < kMinSaturationGap) return;
  cv::Mat part;
  cv::compare(saturation, level, part, cv::CMP_GT);
  cv::bitwise_and(part, pixels, part);
  if (!open_kernel_.empty()) cv::morphologyEx(part, part, cv::MORPH_OPEN, open_kernel_);
  if (!close_kernel_.empty()) cv::morphologyEx(part, part, cv::MORPH_CLOSE, close_kernel_);
  std::vector<std::vector<cv::Point>> parts;
  cv::findContours(part, parts, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE, roi.tl());
  for (const std::vector<cv::Point>& outline : parts) {
    if (cv::contourArea(outline) >= config_.min_area) judge(outline, hsv, spec, candidates);
  }
}

cv::Mat ColourBlobDetector::mask(const cv::Mat& bgr, const std::string& name) const {
  if (bgr.empty() || bgr.type() != CV_8UC3) return cv::Mat();
  for (const ColourSpec& spec : config_.colours) {
    if (spec.name != name) continue;
    cv::Mat hsv;
    cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
    cv::Mat out;
    cleanedMask(hsv, spec, out);
    return out;
  }
  return cv::Mat();
}

void ColourBlobDetector::drawDebug(cv::Mat& bgr, const BlobResult& blobs) {
  for (const ColourBlob& blob : blobs.colours) {
    if (!blob.found) continue;
    cv::drawContours(bgr, std::vector<std::vector<cv::Point>>{blob.contour}, 0,
                     cv::Scalar(255, 255, 255), 2);
    cv::circle(bgr, blob.circle_centre, static_cast<int>(blob.circle_radius),
               cv::Scalar(0, 255, 255), 1);
    cv::putText(bgr, blob.name, blob.bounding_box.tl() - cv::Point(0, 5), cv::FONT_HERSHEY_SIMPLEX,
                0.6, cv::Scalar(255, 255, 255), 2);
  }
}

}  // namespace follow_bot
