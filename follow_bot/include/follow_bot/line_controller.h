// Steering laws on the camera band's error: the lecture's law, and PD with speed taper and the
// lost-line search (LineSearch, which path mode reuses through its pd fallback).
#pragma once

#include "follow_bot/steering_law.h"

namespace follow_bot {

// The lost-line state machine: kFollowing while sightings come; without one, kLost for
// lost_grace s (coasting, turning toward the side the line was last seen on), then kSearching
// for search_timeout s (spinning toward that side), then kGaveUp (stopped). Timed from the last
// sighting; before any sighting there is no side to coast toward, so it searches at once
// (turning left), timed from its first frame.
class LineSearch {
 public:
  explicit LineSearch(const LineSearchConfig& config) : config_(config) {}

  // The line was seen at `stamp` with normalised error `error`, whose sign is the side to turn
  // toward once it is lost (0 keeps the previous side).
  void seen(double stamp, double error);
  // The command for a frame at `stamp` without a sighting.
  Twist2D unseen(double stamp);

  LineState state() const { return state_; }
  void reset() { *this = LineSearch(config_); }

 private:
  LineSearchConfig config_;
  LineState state_ = LineState::kLost;
  bool seen_once_ = false;
  bool timing_ = false;          // outage_start_ is set
  double outage_start_ = 0.0;    // last sighting, or the first frame if none yet
  double turn_direction_ = 1.0;  // +1 left, -1 right: toward where the line was last seen
};

// SteeringMode::kLecture. Keeps no history; the state is kFollowing or kLost.
class LectureLaw : public SteeringLaw {
 public:
  Twist2D step(const LineObservation& frame) override;
  LineState state() const override { return state_; }
  void reset() override { state_ = LineState::kLost; }
  SteeringMode mode() const override { return SteeringMode::kLecture; }

 private:
  LineState state_ = LineState::kLost;
};

// SteeringMode::kPD: PD steering and speed taper (config.pd, within the limits) while the band
// sees the line, LineSearch (config.search) otherwise. Besides SteeringLaw's rules, the
// derivative term is used only when the previous frame also saw the line and the interval is in
// (0, max_derivative_dt], so re-acquiring never kicks.
class PdLaw : public SteeringLaw {
 public:
  // Throws std::invalid_argument with the validate() message when the configuration is unusable;
  // config.mode is not looked at.
  explicit PdLaw(const SteeringConfig& config = SteeringConfig());

  Twist2D step(const LineObservation& frame) override;
  LineState state() const override { return search_.state(); }
  void reset() override;
  SteeringMode mode() const override { return SteeringMode::kPD; }

 private:
  Twist2D follow(const LineMeasurement& measurement, double stamp);

  SteeringConfig config_;
  LineSearch search_;
  bool has_stamp_ = false;
  double last_stamp_ = 0.0;
  bool has_previous_error_ = false;
  double previous_error_ = 0.0;
  double previous_error_stamp_ = 0.0;
};

}  // namespace follow_bot
