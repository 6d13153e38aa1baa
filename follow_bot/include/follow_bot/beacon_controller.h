// Colour-beacon behaviours on top of ColourBlobDetector: range and bearing to a known object,
// and a controller for the lecture's two beacon tasks (Lab 5: follow green, stop on red;
// Exercise 10: drive up to an object and stop facing it at a set distance).
//
// Conventions: base_link and the camera follow ground_projection.h. The bearing of a pixel
// column u is atan((u - cx) / fx), positive when the object is right of the optical axis (as
// the line controller's error), so steering toward it is angular = -k * bearing (REP-103:
// positive angular turns left).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot/BeaconChaserDefaults.h"
#include "follow_bot/BeaconTargetDefaults.h"
#include "follow_bot/colour_blobs.h"
#include "follow_bot/common.h"
#include "follow_bot_common/config_fields.h"
#include "follow_bot_common/enum_names.h"
#include "follow_bot_common/ground_projection.h"
#include "follow_bot_common/velocity_limiter.h"

namespace follow_bot {

// ---- Range to an object --------------------------------------------------------------------

enum class BeaconShape {
  kSphere,  // a ball resting on the floor
  kBox,     // a box standing on the floor, one vertical face toward the camera
};

inline constexpr EnumName<BeaconShape> kBeaconShapeNames[] = {{BeaconShape::kSphere, "sphere"},
                                                              {BeaconShape::kBox, "box"}};
inline std::optional<BeaconShape> parseBeaconShape(std::string_view name) {
  return valueIn(kBeaconShapeNames, name);
}
inline const char* toString(BeaconShape shape) { return nameIn(kBeaconShapeNames, shape); }

struct BeaconObject {
  // Defaults from cfg/BeaconTarget.cfg (the ~target_* parameters): the dumpster world's box.
  BeaconShape shape = *parseBeaconShape(BeaconTargetDefaults::target_shape);
  // Sphere: its radius. Box: the width of the face toward the camera.
  double size_m = BeaconTargetDefaults::target_size;
  // Box only: how far its footprint reaches behind that face, to aim at its centre (boxCentre).
  double depth_m = BeaconTargetDefaults::target_depth;
};

// Empty when the object is usable, otherwise a message naming the first bad field.
std::string validate(const BeaconObject& object);

// Ranges are the horizontal distance from base_link's origin (the robot's centre) to the
// object's footprint on the floor: for a sphere, the distance to its centre minus its radius;
// for a box, the distance to the nearest point of its rectangle. This is what the harness
// scores as the target's final_distance.
struct RangeEstimate {
  // From the apparent size. Sphere: exact (see sphereCentreFromCircle), needs the whole ball in
  // the frame. Box: rangeFromWidth on the bounding-box width plus the camera's x offset, which
  // assumes a level camera looking squarely at the face; needs both sides of the box in the
  // frame.
  std::optional<double> from_size;
  // Box only: the nearest floor point on the blob's outline, each outline pixel's centre put
  // through pixelToGround. Outline points above the floor project beyond the object, so the
  // minimum is the nearest visible floor contact, right for any view of the face while the
  // nearest point of the footprint is in the frame. Needs the bottom edge in the frame (below
  // the horizon, not touching the last row). Pixel centres rather than lower edges, because
  // the harness draws box faces with cv::fillConvexPoly(LINE_AA), which spills about half a
  // pixel past the true edge: on its dumpster frames this reads within 4 mm at 1 m (one row is
  // 6 mm there, 10 cm at 6 m). A ball's outline meets the floor behind its nearest point, so
  // spheres leave this empty.
  std::optional<double> from_ground;

  // The controller's choice: a box's ground-contact range (its face is wider than the frame
  // near the default stop distance, 1.8 m at 1 m spans ~1000 px, and the contact row is
  // exact), falling back to its width; a sphere's size range.
  std::optional<double> best() const { return from_ground ? from_ground : from_size; }
};

// The depth along the optical axis of a face of `width_m` seen squarely, spanning `width_px`
// pixels with focal length `focal_px`: focal_px * width_m / width_px. Empty unless all are
// finite and > 0.
std::optional<double> rangeFromWidth(double focal_px, double width_m, double width_px);

// The centre of a sphere of radius `radius_m` in base_link, from the minimum enclosing circle
// of its silhouette. Exact for a pinhole camera: the silhouette is an ellipse whose major axis
// lies on the line through the principal point, so its enclosing circle's ends on that line
// are the rays at theta -+ alpha from the optical axis, where theta is the angle to the
// sphere's centre and alpha its angular radius; the optical centre is radius_m / sin(alpha)
// from the centre. (The familiar f * r / radius_px is that distance times cos(alpha): 2 % short
// 1 m from a 0.2 m ball's centre, and more off-axis, where the ellipse stretches.) Uses
// the mean focal length sqrt(fx * fy). Empty for a non-positive radius or unusable input.
std::optional<cv::Point3d> sphereCentreFromCircle(const CameraGeometry& camera,
                                                  const cv::Point2d& circle_centre,
                                                  double circle_radius_px, double radius_m);

// A blob of a frame of `frame_size` as the rectified camera (fx, fy, cx, cy) sees it. Raw frames
// through a lens (camera.lens) shrink and bend a blob, the more the further it is off the axis,
// so its contour points go through rectifyPixels and every measure is the rectified contour's;
// without a lens, the blob's own measures.
struct RectifiedBlob {
  std::vector<cv::Point2d> contour;
  double area = 0.0;     // px^2 enclosed (cv::contourArea)
  cv::Point2d centroid;  // of that area (contour moments)
  // The area of the part inside a rectified frame of the same size (the contour's points clamped
  // to the outermost pixel centres), as a frame rectified by image_proc shows it: a barrel lens
  // sees wider than its rectified frame, and close_area is an area on such a frame, where a near
  // ball is cut by the bottom edge.
  double area_in_frame = 0.0;
  cv::Point2d circle_centre;   // minimum enclosing circle
  double circle_radius = 0.0;  // px
  double width = 0.0;          // px, inclusive as a bounding box's
};
RectifiedBlob rectifyBlob(const ColourBlob& blob, const CameraGeometry& camera,
                          const cv::Size& frame_size);

// The centre (base_link) of the sphere of radius `radius_m` a found blob of a frame of the given
// size shows: sphereCentreFromCircle on the rectified blob. Empty when the blob touches the
// frame's edge (the circle would not be the whole ball's) or nothing fits.
std::optional<cv::Point3d> sphereCentre(const ColourBlob& blob, int image_width, int image_height,
                                        const CameraGeometry& camera, double radius_m);

// A box's near face on the floor, in base_link: where the silhouette meets the floor, the
// lowest pixel of each column (pixel centres through the lens and pixelToGround) fitted by a
// line. Contacts twice as far as the nearest, then those off the first fit by more than 5 % of
// their range (5 cm at least), are not the face (another object of the colour touching the
// silhouette and standing elsewhere, the leaning side edges of a pitched camera's view) and are
// left out of the second fit. Empty unless the blob is found, its bottom edge is in the frame
// and 10 or more contacts fit.
struct BoxFace {
  cv::Point2d foot;                 // the face's point nearest the robot (the perpendicular's foot)
  cv::Point2d along;                // unit, along the face from the frame's left to its right
  cv::Point2d eye;                  // the camera's optical centre seen from above
  cv::Point2d leftmost, rightmost;  // the contacts on the face furthest along it either way
  cv::Point2d behind() const { return cv::Point2d(-along.y, along.x); }  // unit, away from us
};
std::optional<BoxFace> boxFace(const ColourBlob& blob, int image_width, int image_height,
                               const CameraGeometry& camera);

// The centre (base_link x, y) of a box target from its face and the frame's cuts. Each face end
// in view is where the ray through the last contact on that side meets the face (seen from
// above, that ray passes through the box's corner whether its pixel is on the bottom edge or up
// the side edge; the contact itself a row's error slides along the ray). With both ends in
// view the face's middle is between them, if they are object.size_m apart within 15 % (else
// this is another face, seen from beside the box); with one, object.size_m / 2 along the face
// from it. The centre is object.depth_m / 2 behind that middle. Empty for a sphere, with both
// sides cut, or for a face of another length. Unlike the silhouette's middle, neither the
// frame's edge (near the stop the face is wider than the view: centring the visible part leaves
// the robot at rest with the box's edge on the frame's, a few degrees off) nor another object
// of the colour touching the silhouette (a green poster on the wall behind it) moves it.
std::optional<cv::Point2d> boxCentre(const BoxFace& face, bool cut_left, bool cut_right,
                                     const BeaconObject& object);

// Both range estimates for a found blob of `object` in a frame of the given size (an estimate
// whose condition above fails is left empty; a blob that is not found gives neither).
RangeEstimate estimateRange(const ColourBlob& blob, int image_width, int image_height,
                            const CameraGeometry& camera, const BeaconObject& object);

// ---- Controller ----------------------------------------------------------------------------

enum class BeaconMode {
  // Lab 5: search for green, drive toward it until it looks big, stop while red is in view.
  kFollowGreenStopRed,
  // Exercise 10: drive up to one object and stop stop_distance from it, facing it.
  kApproach,
};

inline constexpr EnumName<BeaconMode> kBeaconModeNames[] = {
    {BeaconMode::kFollowGreenStopRed, "follow_green_stop_red"},
    {BeaconMode::kApproach, "approach"}};
inline std::optional<BeaconMode> parseBeaconMode(std::string_view name) {
  return valueIn(kBeaconModeNames, name);
}
inline const char* toString(BeaconMode mode) { return nameIn(kBeaconModeNames, mode); }

enum class BeaconState {
  kSearching,     // the target is not in view: spin in place toward where it was last seen
  kApproaching,   // the target is in view: turn toward it and drive
  kHolding,       // follow mode: the target looks close (area >= close_area), stand still
  kStoppedByRed,  // follow mode: the stop colour is in view, stand still
  kLost,          // approach mode: the target just vanished, stand still for lost_hold s
  kArrived,       // approach mode: at stop_distance and facing the target, stand still
};
inline constexpr EnumName<BeaconState> kBeaconStateNames[] = {
    {BeaconState::kSearching, "searching"}, {BeaconState::kApproaching, "approaching"},
    {BeaconState::kHolding, "holding"},     {BeaconState::kStoppedByRed, "stopped_by_red"},
    {BeaconState::kLost, "lost"},           {BeaconState::kArrived, "arrived"}};
inline const char* toString(BeaconState state) { return nameIn(kBeaconStateNames, state); }

// Defaults of the parameters cfg/BeaconChaser.cfg declares: BeaconChaserDefaults (generated).
struct BeaconControllerConfig {
  BeaconMode mode = BeaconMode::kFollowGreenStopRed;
  double search_rate =
      BeaconChaserDefaults::search_rate;  // rad/s, spin while the target is out of view

  // Follow mode. Colour names refer to the detector's ColourSpec names.
  std::string follow_colour = BeaconChaserDefaults::follow_colour;
  std::string stop_colour = BeaconChaserDefaults::stop_colour;
  // A 0.2 m ball covers ~30000 px^2 about 1.1 m from its centre, ~85000 px^2 0.50 m from its
  // surface (what the scenarios run with; cfg/BeaconChaser.cfg's default).
  double close_area =
      BeaconChaserDefaults::close_area;  // px^2: hold once the follow blob is at least this big
  double stop_min_area =
      BeaconChaserDefaults::stop_min_area;  // px^2: a stop blob at least this big stops the robot
  // The robot stays stopped this long after the stop colour was last seen, so one frame that
  // misses it does not let the robot lurch forward.
  double stop_release_delay = BeaconChaserDefaults::stop_release_delay;  // s
  double approach_speed = BeaconChaserDefaults::approach_speed;          // m/s
  // Within approach_taper (a fraction) of the hold distance the speed falls in proportion to
  // the distance left, estimated from the area as a sphere's (distance ~ 1 / sqrt(area)), down
  // to creep_speed: after the last forward command a real base moves on for its delay and motor
  // lag (0.17-0.3 s in the harsh profile), which from full speed put the robot 34-54 mm nearer
  // than the hold.
  double approach_taper = BeaconChaserDefaults::approach_taper;
  double creep_speed = BeaconChaserDefaults::creep_speed;  // m/s
  // Once holding, the robot holds until the distance left exceeds this fraction of the hold
  // distance (2 cm of 0.7 m): it rests at the hold's edge, where exposure drift and noise move
  // the area by a percent or two from frame to frame, and each dip would restart a creep.
  double hold_release = 0.03;
  // angular = -turn_gain * e with e = (centroid_x - width / 2) / (width / 2) in [-1, 1]; e = 1
  // is the image edge, 30 deg off the axis, for the harness camera.
  double turn_gain = BeaconChaserDefaults::turn_gain;  // rad/s per unit of normalised error

  // Approach mode.
  std::string target_colour = BeaconChaserDefaults::target_colour;
  BeaconObject target;
  // The rgb and dumpster worlds' camera: the harness defaults, level (no camera block means
  // pitch_deg 0). Set from CameraInfo and the camera's mounting.
  CameraGeometry camera = [] {
    CameraGeometry level;
    level.pitch_rad = 0.0;
    return level;
  }();
  double stop_distance =
      BeaconChaserDefaults::stop_distance;  // m, target range (see RangeEstimate) to stop at
  // linear = k_range * (range - stop_distance), clamped to [0, max_linear] (to
  // [-max_linear, max_linear] with allow_reverse): a first-order approach, no overshoot.
  double k_range = BeaconChaserDefaults::k_range;        // 1/s
  double max_linear = BeaconChaserDefaults::max_linear;  // m/s
  bool allow_reverse = false;
  // The linear speed is scaled by max(0, 1 - |bearing| / speed_taper_bearing), so a robot
  // facing away turns toward the object before driving and arrives along a straight line: a
  // sideways drift would show later as a bearing error, once a box too close to fit in the
  // frame no longer shows its centre. 3 deg: a base 150 ms late with a 0.2 s motor lag must
  // not reach that point from 2 m still turning.
  double speed_taper_bearing = 0.05;  // rad
  double k_bearing =
      BeaconChaserDefaults::k_bearing;  // angular = -k_bearing * bearing, rad/s per rad
  double max_angular = BeaconChaserDefaults::max_angular;  // rad/s, bound on that angular
  // Arrived when |range - stop_distance| and |bearing| are below these. The robot closes in
  // from one side and stops on the first frame inside, so it ends near the tolerance: half of
  // the 1 cm goal leaves room for the range's pixel quantisation (6 mm per row at 1 m).
  double distance_tolerance = 0.005;                                // m
  double bearing_tolerance = 1.0 * 3.14159265358979323846 / 180.0;  // rad
  // Once arrived, the robot stays arrived until the range error or the bearing exceeds these,
  // wider than the tolerances above: at rest near the stop the measured range jitters by a
  // pixel row (6 mm at 1 m) with exposure drift and sensor noise, and each excursion past
  // distance_tolerance would restart the approach for a creep of a few mm/s. 15 mm is the
  // dumpster family's bound on the final distance.
  double distance_release = 0.015;                                // m
  double bearing_release = 3.0 * 3.14159265358979323846 / 180.0;  // rad
  double lost_hold = 1.0;  // s to stand still after losing the target before searching

  static constexpr auto fields() {
    using C = BeaconControllerConfig;
    return std::make_tuple(cfgField("search_rate", &C::search_rate, atLeast(0.0)),
                           field("follow_colour", &C::follow_colour),
                           field("stop_colour", &C::stop_colour),
                           cfgField("close_area", &C::close_area, atLeast(0.0)),
                           cfgField("stop_min_area", &C::stop_min_area, atLeast(0.0)),
                           cfgField("stop_release_delay", &C::stop_release_delay, atLeast(0.0)),
                           cfgField("approach_speed", &C::approach_speed, atLeast(0.0)),
                           cfgField("approach_taper", &C::approach_taper, atLeast(0.0)),
                           cfgField("creep_speed", &C::creep_speed, atLeast(0.0)),
                           field("hold_release", &C::hold_release, atLeast(0.0)),
                           cfgField("turn_gain", &C::turn_gain, atLeast(0.0)),
                           field("target_colour", &C::target_colour),
                           cfgField("stop_distance", &C::stop_distance, positive()),
                           cfgField("k_range", &C::k_range, positive()),
                           cfgField("max_linear", &C::max_linear, positive()),
                           field("allow_reverse", &C::allow_reverse),
                           field("speed_taper_bearing", &C::speed_taper_bearing, positive()),
                           cfgField("k_bearing", &C::k_bearing, atLeast(0.0)),
                           cfgField("max_angular", &C::max_angular, positive()),
                           field("distance_tolerance", &C::distance_tolerance, positive()),
                           field("bearing_tolerance", &C::bearing_tolerance, positive()),
                           field("distance_release", &C::distance_release),
                           field("bearing_release", &C::bearing_release),
                           field("lost_hold", &C::lost_hold, atLeast(0.0)));
  }
};

// Empty when the configuration is usable, otherwise a message naming the first bad field,
// e.g. "stop_distance must be > 0, got 0".
std::string validate(const BeaconControllerConfig& config);

// Empty when every colour the controller's mode uses is one the detector measures, otherwise a
// message naming the missing colour (the controller treats a missing colour as never seen).
std::string checkColoursDetected(const BeaconControllerConfig& controller,
                                 const ColourBlobConfig& detector);

class BeaconController {
 public:
  // Throws std::invalid_argument with the validate() message when the configuration is unusable.
  explicit BeaconController(const BeaconControllerConfig& config = BeaconControllerConfig());

  // The command for one frame's blobs. `stamp` is the frame's time in seconds. Never returns a
  // non-finite value. A non-finite stamp or a rejected frame (blobs.ok() false) gives a zero
  // twist and leaves the state alone; a stamp earlier than the previous one (sim or bag
  // restart) resets the controller first.
  //
  // Follow mode, in priority order: a stop-colour blob (found, area >= stop_min_area) in view
  // or seen within stop_release_delay -> zero, kStoppedByRed; no follow-colour blob ->
  // kSearching; area >= close_area (or, once holding, the distance left within hold_release)
  // -> zero, kHolding; otherwise kApproaching: approach_speed
  // (slowed within approach_taper of the hold, not below creep_speed) and
  // angular = -turn_gain * e. Areas and the centroid are the rectified blob's
  // (rectifyBlob with config.camera; close_area against its area_in_frame), so raw frames
  // through a lens hold and steer as rectified ones.
  //
  // Approach mode: with the target in view, bearing from its column and range from
  // estimateRange().best(). A sphere's column is its centroid; a box's is the middle of its
  // silhouette, because seen obliquely its nearer face outweighs the rest and pulls the
  // centroid off the box's centre (~3 deg at the stop point from 30 deg off its axis). But a
  // box whose face boxFace finds and boxCentre places is aimed at by that centre's bearing from
  // base_link. Arrived (zero, kArrived) when both are within tolerance, and kept while both
  // stay within the release bounds; otherwise kApproaching with the linear and angular laws of
  // the config. Without a range (too close to see its bottom edge, or partly out of frame) it
  // only turns. The point aimed at is carried from frame to frame by the commands sent (a late
  // base makes them all in the end): a box spilling over both sides of the frame has no
  // observable centre and the carried point stands (the turn a late base was still making as
  // the face filled the view is finished, not left), or the bearing is zero if none was seen;
  // a centre placed from one end in view moves it 0.15 of the way. Turns under 1e-4 rad are
  // not commanded. When the target vanishes after being seen the robot stands still (kLost) for
  // lost_hold s, then searches; a controller that has never seen it searches at once (to the
  // left).
  Twist2D update(const BlobResult& blobs, double stamp);

  BeaconState state() const { return state_; }
  // The last range and bearing used in approach mode (empty when the target was not seen).
  const std::optional<double>& lastRange() const { return last_range_; }
  const std::optional<double>& lastBearing() const { return last_bearing_; }
  const BeaconControllerConfig& config() const { return config_; }

  // Forgets all history, as if newly constructed.
  void reset();

 private:
  Twist2D followGreenStopRed(const BlobResult& blobs, double stamp);
  Twist2D approach(const BlobResult& blobs, double stamp);
  Twist2D search();

  BeaconControllerConfig config_;
  BeaconState state_ = BeaconState::kSearching;
  bool has_stamp_ = false;
  double last_stamp_ = 0.0;
  bool stop_seen_ = false;
  double stop_last_seen_ = 0.0;
  bool target_seen_ = false;
  double target_last_seen_ = 0.0;
  double search_direction_ = 1.0;  // +1 left, -1 right: toward where the target was last seen
  std::optional<double> last_range_;
  std::optional<double> last_bearing_;
  // Approach mode: the point aimed at (base_link), as last seen or carried since.
  std::optional<cv::Point2d> aimed_at_;
  Twist2D last_command_;
  double last_command_stamp_ = 0.0;
};

}  // namespace follow_bot
