// The SteeringLaw interface: every law reproduces the commands of the code it replaced, the
// factory picks the law ~mode names, and pd and path share one lost-line search.
#include "follow_bot/steering_law.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "follow_bot/line_controller.h"
#include "follow_bot/line_path.h"

namespace follow_bot {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr LineState kFollowing = LineState::kFollowing;
constexpr LineState kLost = LineState::kLost;
constexpr LineState kSearching = LineState::kSearching;
constexpr LineState kGaveUp = LineState::kGaveUp;

struct ScriptedFrame {
  LineMeasurement measurement;
  double stamp = 0.0;
};

// The 20-row band of a 640x480 frame around `row`, seeing the line at `column`; found when
// pixel_count reaches the default min_pixels (30).
BandMeasurement scriptedBand(double column, double row, int pixel_count = 400,
                             double confidence = 1.0) {
  BandMeasurement band;
  band.row_begin = static_cast<int>(row - 9.5);
  band.row_end = band.row_begin + 20;
  band.pixel_count = pixel_count;
  band.found = pixel_count >= 30;
  band.centroid_x = column;
  band.centroid_y = row;
  band.centre_pixel_count = pixel_count;  // the whole line: no run cut by the image edge
  band.centre_found = band.found;
  band.centre_x = column;
  band.centre_y = row;
  band.spans = {{row, column - 5.0, column + 5.0}};  // a 10 px wide line
  band.error_px = column - 320.0;
  band.error_normalised = band.error_px / 320.0;
  band.confidence = confidence;
  return band;
}

std::vector<ScriptedFrame> scriptedFrames() {
  constexpr double kBandRow = 369.5;
  constexpr double kLookAheadRow = 273.5;
  constexpr double kFrameDt = 1.0 / 30.0;
  std::vector<ScriptedFrame> frames;
  double stamp = 100.0;
  const auto add = [&](const LineMeasurement& m, double dt) {
    stamp += dt;
    frames.push_back({m, stamp});
  };
  const auto seen = [&](double column) {
    LineMeasurement m;
    m.image_width = 640;
    m.image_height = 480;
    m.band = scriptedBand(column, kBandRow);
    return m;
  };
  LineMeasurement none;  // a processed frame without line pixels
  none.image_width = 640;
  none.image_height = 480;
  none.band.row_begin = 360;
  none.band.row_end = 380;

  // A gently winding line, the look-ahead band seeing further round the bends for a while.
  for (int i = 0; i < 24; ++i) {
    LineMeasurement m = seen(320.0 + 60.0 * std::sin(0.25 * i));
    if (i >= 8 && i < 16)
      m.look_ahead = scriptedBand(320.0 + 90.0 * std::sin(0.25 * i + 0.6), kLookAheadRow);
    add(m, kFrameDt);
  }
  LineMeasurement faint = seen(350.0);
  faint.band.confidence = 0.1;
  add(faint, kFrameDt);
  LineMeasurement rejected = seen(350.0);
  rejected.error = "empty image";
  add(rejected, kFrameDt);
  LineMeasurement few = seen(360.0);  // below min_pixels: only the lecture follows
  few.band = scriptedBand(360.0, kBandRow, 5, 0.0);
  add(few, kFrameDt);
  for (int i = 0; i < 8; ++i) add(seen(290.0 - 5.0 * i), kFrameDt);  // line to the left
  add(seen(280.0), 0.6);  // a frame gap: no derivative, path memory cleared
  for (int i = 0; i < 6; ++i) add(seen(275.0 + 2.0 * i), kFrameDt);
  for (int i = 0; i < 10; ++i) add(none, kFrameDt);  // path still drives its memory
  for (int i = 0; i < 6; ++i) add(none, 0.4);        // lost, then searching
  add(none, 12.0);                                   // gave up
  LineMeasurement ahead_only = none;
  ahead_only.look_ahead = scriptedBand(380.0, kLookAheadRow);
  add(ahead_only, kFrameDt);
  for (int i = 0; i < 4; ++i) add(seen(370.0 - 10.0 * i), kFrameDt);
  add(seen(330.0), -50.0);  // the clock jumps back (sim restart)
  for (int i = 0; i < 3; ++i) add(seen(325.0 + 3.0 * i), kFrameDt);
  frames.push_back({seen(320.0), std::numeric_limits<double>::quiet_NaN()});
  for (int i = 0; i < 3; ++i) add(seen(318.0 - 2.0 * i), kFrameDt);
  return frames;
}

struct Command {
  double linear;
  double angular;
  LineState state;
};

// Per frame of scriptedFrames(): the lecture, pd and path laws' commands and states (path fed
// its own previous command as the motion, the harness camera), as LineController (modes lecture
// and pd) and LinePathFollower gave them at commit ae37336, before the SteeringLaw interface.
const Command kCaptured[][3] = {
    {{0.2, -0, kFollowing}, {0.3, -0, kFollowing}, {0.3, -0, kFollowing}},
    {{0.2, -0.148442375552714, kFollowing},
     {0.29165011637516, -0.208747090621012, kFollowing},
     {0.3, 0, kFollowing}},
    {{0.2, -0.287655323162522, kFollowing},
     {0.283819388072108, -0.265350571116634, kFollowing},
     {0.3, 0, kFollowing}},
    {{0.2, -0.408983256014001, kFollowing},
     {0.276994691849212, -0.305455838304831, kFollowing},
     {0.3, 0, kFollowing}},
    {{0.2, -0.504882590884738, kFollowing},
     {0.271600354262733, -0.326569340918542, kFollowing},
     {0.3, 0, kFollowing}},
    {{0.2, -0.569390771613351, kFollowing},
     {0.267971769096749, -0.327378343626837, kFollowing},
     {0.3, 0, kFollowing}},
    {{0.2, -0.598496991962433, kFollowing},
     {0.266334544202113, -0.307832546559655, kFollowing},
     {0.3, 0, kFollowing}},
    {{0.2, -0.590391568124362, kFollowing},
     {0.266790474293005, -0.269147212710103, kFollowing},
     {0.3, 0, kFollowing}},
    {{0.2, -0.545578456095409, kFollowing},
     {0.266862395200951, -0.202248780750314, kFollowing},
     {0.3, 0, kFollowing}},
    {{0.2, -0.466843918132753, kFollowing},
     {0.267496618394299, -0.115753467234419, kFollowing},
     {0.0966421603738622, 1.5, kFollowing}},
    {{0.2, -0.359083286462374, kFollowing},
     {0.270151744428319, -0.022061163768694, kFollowing},
     {0.116643182252122, 1.5, kFollowing}},
    {{0.2, -0.228996595231399, kFollowing},
     {0.27466269042611, 0.0730027960086577, kFollowing},
     {0.3, -0.167066842678516, kFollowing}},
    {{0.2, -0.0846720048359202, kFollowing},
     {0.273975349529688, 0.163527795513488, kFollowing},
     {0.3, 0.692550387100842, kFollowing}},
    {{0.2, 0.064917080718065, kFollowing},
     {0.263157260866272, 0.243885428727294, kFollowing},
     {0.3, -0.217702171579215, kFollowing}},
    {{0.2, 0.210469936613772, kFollowing},
     {0.254629875277283, 0.309079447222716, kFollowing},
     {0.3, -0.217702171579215, kFollowing}},
    {{0.2, 0.342936791245406, kFollowing},
     {0.248923384296925, 0.355056402691804, kFollowing},
     {0.3, -0.217702171579215, kFollowing}},
    {{0.2, 0.454081497184757, kFollowing},
     {0.274457915783357, 0.317048863623502, kFollowing},
     {0.3, -0.217702171579215, kFollowing}},
    {{0.2, 0.53699361493715, kFollowing},
     {0.269794109159785, 0.329445867394662, kFollowing},
     {0.3, -0.217702171579215, kFollowing}},
    {{0.2, 0.586518070599058, kFollowing},
     {0.267008358528803, 0.32135952277635, kFollowing},
     {0.3, -0.300919084505003, kFollowing}},
    {{0.2, 0.599575673385227, kFollowing},
     {0.266273868372081, 0.293292599511359, kFollowing},
     {0.3, -0.37018302588297, kFollowing}},
    {{0.2, 0.575354564797883, kFollowing},
     {0.267636305730119, 0.246990162948372, kFollowing},
     {0.3, -0.421167386488194, kFollowing}},
    {{0.2, 0.515360696055955, kFollowing},
     {0.271010960846852, 0.185331074330668, kFollowing},
     {0.3, -0.451575394701402, kFollowing}},
    {{0.2, 0.423324195342235, kFollowing},
     {0.276188014011999, 0.112148997147555, kFollowing},
     {0.3, -0.460707649659096, kFollowing}},
    {{0.2, 0.304967446499555, kFollowing},
     {0.2828455811344, 0.031994038506648, kFollowing},
     {0.3, -0.448810374797255, kFollowing}},
    {{0.2, -0.3, kFollowing}, {0.05, 0.4, kLost}, {0.3, -0.448810374797255, kFollowing}},
    {{0, 0, kLost}, {0.05, 0.4, kLost}, {0.3, -0.414440926614049, kFollowing}},
    {{0.2, -0.4, kFollowing}, {0.05, 0.4, kLost}, {0.3, -0.290237065829015, kFollowing}},
    {{0.2, 0.3, kFollowing},
     {0.283125, 0.140625, kFollowing},
     {0.3, 0.177495200504189, kFollowing}},
    {{0.2, 0.35, kFollowing},
     {0.2803125, 0.210937500000003, kFollowing},
     {0.3, 0.396096817523671, kFollowing}},
    {{0.2, 0.4, kFollowing},
     {0.2775, 0.234375000000003, kFollowing},
     {0.3, 0.396096817523671, kFollowing}},
    {{0.2, 0.45, kFollowing},
     {0.2746875, 0.257812500000003, kFollowing},
     {0.3, 0.445671659569964, kFollowing}},
    {{0.2, 0.5, kFollowing},
     {0.271875, 0.281250000000003, kFollowing},
     {0.3, 0.480646684857268, kFollowing}},
    {{0.2, 0.55, kFollowing},
     {0.2690625, 0.304687500000003, kFollowing},
     {0.3, 0.497845901985112, kFollowing}},
    {{0.2, 0.6, kFollowing},
     {0.26625, 0.328125000000003, kFollowing},
     {0.3, 0.495648760472874, kFollowing}},
    {{0.2, 0.65, kFollowing},
     {0.2634375, 0.351562500000003, kFollowing},
     {0.3, 0.473451420515932, kFollowing}},
    {{0.2, 0.4, kFollowing}, {0.2775, 0.1875, kFollowing}, {0.3, 0.108883864572132, kFollowing}},
    {{0.2, 0.45, kFollowing},
     {0.2746875, 0.257812500000003, kFollowing},
     {0.3, 0.108883864572132, kFollowing}},
    {{0.2, 0.43, kFollowing},
     {0.2758125, 0.182812499999999, kFollowing},
     {0.3, 0.108883864572132, kFollowing}},
    {{0.2, 0.41, kFollowing},
     {0.2769375, 0.173437499999999, kFollowing},
     {0.3, 0.108883864572132, kFollowing}},
    {{0.2, 0.39, kFollowing},
     {0.2780625, 0.164062499999999, kFollowing},
     {0.3, 0.108883864572132, kFollowing}},
    {{0.2, 0.37, kFollowing},
     {0.2791875, 0.154687499999999, kFollowing},
     {0.3, 0.108883864572132, kFollowing}},
    {{0.2, 0.35, kFollowing},
     {0.2803125, 0.145312499999999, kFollowing},
     {0.3, 0.108883864572132, kFollowing}},
    {{0, 0, kLost}, {0.05, 0.4, kLost}, {0.3, 0.108883864572132, kFollowing}},
    {{0, 0, kLost}, {0.05, 0.4, kLost}, {0.3, 0.108883864572132, kFollowing}},
    {{0, 0, kLost}, {0.05, 0.4, kLost}, {0.3, 0.108883864572132, kFollowing}},
    {{0, 0, kLost}, {0.05, 0.4, kLost}, {0.3, 0.108883864572132, kFollowing}},
    {{0, 0, kLost}, {0.05, 0.4, kLost}, {0.3, 0.108883864572132, kFollowing}},
    {{0, 0, kLost}, {0.05, 0.4, kLost}, {0.3, 0.108883864572132, kFollowing}},
    {{0, 0, kLost}, {0.05, 0.4, kLost}, {0.3, 0.108883864572133, kFollowing}},
    {{0, 0, kLost}, {0.05, 0.4, kLost}, {0.3, 0.108883864572133, kFollowing}},
    {{0, 0, kLost}, {0.05, 0.4, kLost}, {0.3, 0.108883864572133, kFollowing}},
    {{0, 0, kLost}, {0.05, 0.4, kLost}, {0.3, 0.108883864572133, kFollowing}},
    {{0, 0, kLost}, {0.05, 0.4, kLost}, {0.3, 0.0596853682264848, kFollowing}},
    {{0, 0, kLost}, {0, 0.6, kSearching}, {0.3, 0.0043681950435046, kFollowing}},
    {{0, 0, kLost}, {0, 0.6, kSearching}, {0.3, -0.338278107947627, kFollowing}},
    {{0, 0, kLost}, {0, 0.6, kSearching}, {0.05, 0.4, kLost}},
    {{0, 0, kLost}, {0, 0.6, kSearching}, {0.05, 0.4, kLost}},
    {{0, 0, kLost}, {0, 0.6, kSearching}, {0, 0.6, kSearching}},
    {{0, 0, kLost}, {0, 0, kGaveUp}, {0, 0, kGaveUp}},
    {{0, 0, kLost}, {0, 0, kGaveUp}, {0.3, -0.100834507524883, kFollowing}},
    {{0.2, -0.5, kFollowing},
     {0.271875, -0.234375, kFollowing},
     {0.3, -0.13557129341649, kFollowing}},
    {{0.2, -0.4, kFollowing},
     {0.2775, -0.0937499999999947, kFollowing},
     {0.3, -0.13557129341649, kFollowing}},
    {{0.2, -0.3, kFollowing},
     {0.283125, -0.0468749999999947, kFollowing},
     {0.3, -0.13557129341649, kFollowing}},
    {{0.2, -0.2, kFollowing},
     {0.28875, 5.32907051820075e-15, kFollowing},
     {0.3, -0.13557129341649, kFollowing}},
    {{0.2, -0.1, kFollowing},
     {0.294375, -0.046875, kFollowing},
     {0.3, -0.0274006906518603, kFollowing}},
    {{0.2, -0.05, kFollowing},
     {0.2971875, 0.0234375000000027, kFollowing},
     {0.3, -0.0274006906518615, kFollowing}},
    {{0.2, -0.08, kFollowing},
     {0.2955, -0.0656250000000016, kFollowing},
     {0.3, -0.0274006906518629, kFollowing}},
    {{0.2, -0.11, kFollowing},
     {0.2938125, -0.0796875000000016, kFollowing},
     {0.3, -0.0274006906518643, kFollowing}},
    {{0.2, -0, kFollowing}, {0, 0, kFollowing}, {0, 0, kFollowing}},
    {{0.2, 0.02, kFollowing},
     {0.298875, 0.131250000000007, kFollowing},
     {0.3, -0.0274006906518643, kFollowing}},
    {{0.2, 0.04, kFollowing},
     {0.29775, 0.0375000000000011, kFollowing},
     {0.3, -0.0274006906518657, kFollowing}},
    {{0.2, 0.06, kFollowing},
     {0.296625, 0.0468750000000011, kFollowing},
     {0.3, -0.0274006906518673, kFollowing}}};

TEST(SteeringLaw, EachLawGivesTheCommandsOfTheCodeItReplaced) {
  const std::vector<ScriptedFrame> frames = scriptedFrames();
  ASSERT_EQ(frames.size(), std::size(kCaptured));
  const SteeringMode modes[] = {SteeringMode::kLecture, SteeringMode::kPD, SteeringMode::kPath};
  for (size_t law = 0; law < std::size(modes); ++law) {
    SteeringConfig config;
    config.mode = modes[law];
    const std::unique_ptr<SteeringLaw> steering = makeSteeringLaw(config, CameraGeometry());
    Twist2D applied;
    for (size_t i = 0; i < frames.size(); ++i) {
      applied = steering->step({frames[i].measurement, frames[i].stamp, applied});
      const Command& expected = kCaptured[i][law];
      EXPECT_NEAR(applied.linear, expected.linear, 1e-12) << toString(modes[law]) << " frame " << i;
      EXPECT_NEAR(applied.angular, expected.angular, 1e-12)
          << toString(modes[law]) << " frame " << i;
      EXPECT_EQ(steering->state(), expected.state) << toString(modes[law]) << " frame " << i;
    }
  }
}

TEST(SteeringLaw, FactoryMakesTheLawTheModeNames) {
  SteeringConfig config;
  config.mode = SteeringMode::kLecture;
  std::unique_ptr<SteeringLaw> law = makeSteeringLaw(config, std::nullopt);
  EXPECT_EQ(law->mode(), SteeringMode::kLecture);
  EXPECT_NE(dynamic_cast<LectureLaw*>(law.get()), nullptr);

  config.mode = SteeringMode::kPD;
  law = makeSteeringLaw(config, CameraGeometry());
  EXPECT_EQ(law->mode(), SteeringMode::kPD);
  EXPECT_NE(dynamic_cast<PdLaw*>(law.get()), nullptr);

  config.mode = SteeringMode::kPath;
  law = makeSteeringLaw(config, CameraGeometry());
  EXPECT_EQ(law->mode(), SteeringMode::kPath);
  EXPECT_NE(dynamic_cast<PathLaw*>(law.get()), nullptr);
  // No camera_info yet: path's own fallback, pd on the same settings.
  law = makeSteeringLaw(config, std::nullopt);
  EXPECT_EQ(law->mode(), SteeringMode::kPD);
  EXPECT_NE(dynamic_cast<PdLaw*>(law.get()), nullptr);
}

TEST(SteeringLaw, FactoryRejectsAnUnusableConfigurationWhateverTheMode) {
  for (SteeringMode mode : {SteeringMode::kLecture, SteeringMode::kPD, SteeringMode::kPath}) {
    SteeringConfig config;
    config.mode = mode;
    config.path.fit_length = 0.0;
    try {
      makeSteeringLaw(config, CameraGeometry());
      ADD_FAILURE() << toString(mode) << " accepted fit_length 0";
    } catch (const std::invalid_argument& error) {
      EXPECT_STREQ(error.what(), "fit_length must be > 0, got 0") << toString(mode);
    }
  }
  CameraGeometry camera;
  camera.height_m = 0.0;
  SteeringConfig path;
  path.mode = SteeringMode::kPath;
  EXPECT_THROW(makeSteeringLaw(path, camera), std::invalid_argument);
}

TEST(SteeringLaw, ValidatesEverySection) {
  auto error_for = [](auto change) {
    SteeringConfig config;
    change(config);
    return validate(config);
  };
  EXPECT_EQ(validate(SteeringConfig()), "");
  EXPECT_EQ(error_for([](SteeringConfig& c) { c.max_linear = 0; }),
            "max_linear must be > 0, got 0");
  EXPECT_EQ(error_for([](SteeringConfig& c) { c.min_linear = 0.5; }),
            "min_linear (0.5) must be <= max_linear (0.3)");
  EXPECT_EQ(error_for([](SteeringConfig& c) { c.max_angular = 0; }),
            "max_angular must be > 0, got 0");
  EXPECT_EQ(error_for([](SteeringConfig& c) { c.pd.kp = -1; }), "kp must be >= 0, got -1");
  EXPECT_EQ(error_for([](SteeringConfig& c) { c.pd.kd = kNaN; }), "kd must be >= 0, got nan");
  EXPECT_EQ(error_for([](SteeringConfig& c) { c.pd.look_ahead_weight = 1.5; }),
            "look_ahead_weight must be in [0, 1], got 1.5");
  EXPECT_EQ(error_for([](SteeringConfig& c) { c.search.search_timeout = kInf; }),
            "search_timeout must be >= 0, got inf");
  EXPECT_EQ(error_for([](SteeringConfig& c) { c.search.lost_linear = 0.4; }),
            "lost_linear (0.4) must be <= max_linear (0.3)");
  EXPECT_EQ(error_for([](SteeringConfig& c) { c.path.lateral_gain = kNaN; }),
            "lateral_gain must be >= 0, got nan");
  EXPECT_EQ(error_for([](SteeringConfig& c) { c.path.max_points = 2; }),
            "max_points must be >= 3, got 2");
  SteeringConfig bad;
  bad.max_linear = -0.1;
  EXPECT_THROW(PdLaw{bad}, std::invalid_argument);
}

TEST(SteeringLaw, NamesModesAndStates) {
  for (SteeringMode mode : {SteeringMode::kLecture, SteeringMode::kPD, SteeringMode::kPath}) {
    EXPECT_EQ(parseSteeringMode(toString(mode)), mode);
  }
  EXPECT_STREQ(toString(SteeringMode::kPath), "path");
  EXPECT_EQ(parseSteeringMode("PID"), std::nullopt);
  EXPECT_EQ(parseSteeringMode("Path"), std::nullopt);
  EXPECT_STREQ(toString(LineState::kGaveUp), "gave_up");
  EXPECT_STREQ(toString(LineState::kSearching), "searching");
}

// Feeds pd and path the same frames (path its own commands as the motion) and returns, for each,
// the commands and states from its first frame without a sighting of its own on.
std::array<std::vector<Command>, 2> searches(const std::vector<LineMeasurement>& frames,
                                             double frame_dt) {
  std::array<std::unique_ptr<SteeringLaw>, 2> laws = {
      std::make_unique<PdLaw>(SteeringConfig()),
      std::make_unique<PathLaw>(SteeringConfig(), CameraGeometry())};
  std::array<std::vector<Command>, 2> searched;
  for (size_t law = 0; law < laws.size(); ++law) {
    Twist2D applied;
    for (size_t i = 0; i < frames.size(); ++i) {
      applied = laws[law]->step({frames[i], i * frame_dt, applied});
      const LineState state = laws[law]->state();
      if (state != kFollowing || !searched[law].empty()) {
        searched[law].push_back({applied.linear, applied.angular, state});
      }
    }
  }
  return searched;
}

void expectSameSearch(const std::vector<Command>& pd, const std::vector<Command>& path) {
  const size_t frames = std::min(pd.size(), path.size());
  ASSERT_GT(frames, 0u);
  for (size_t i = 0; i < frames; ++i) {
    EXPECT_EQ(pd[i].linear, path[i].linear) << i;
    EXPECT_EQ(pd[i].angular, path[i].angular) << i;
    EXPECT_EQ(pd[i].state, path[i].state) << i;
  }
}

// The frame interval is a power of two so that the search's timing is exact in both laws.
constexpr double kSearchFrameDt = 0.125;

TEST(LineSearch, PdAndPathSearchAlikeWithoutEverSeeingTheLine) {
  LineMeasurement none;
  none.image_width = 640;
  none.image_height = 480;
  const auto [pd, path] = searches(std::vector<LineMeasurement>(120, none), kSearchFrameDt);
  ASSERT_EQ(pd.size(), 120u);
  ASSERT_EQ(path.size(), 120u);
  expectSameSearch(pd, path);
  // No side to prefer: search at once, turning left, for search_timeout; then give up.
  EXPECT_EQ(pd[0].state, kSearching);
  EXPECT_EQ(pd[0].angular, 0.6);
  EXPECT_EQ(pd[96].state, kSearching);  // 12 s
  EXPECT_EQ(pd[97].state, kGaveUp);
}

TEST(LineSearch, PdAndPathSearchAlikeOnceTheLineIsLost) {
  LineMeasurement none;
  none.image_width = 640;
  none.image_height = 480;
  // The line seen right of centre for 1 s, then never again.
  std::vector<LineMeasurement> frames(8, none);
  for (LineMeasurement& frame : frames) frame.band = scriptedBand(400.0, 369.5);
  frames.resize(8 + 160, none);
  const auto [pd, path] = searches(frames, kSearchFrameDt);
  // path drives its remembered line first, so its search starts later and has fewer frames here.
  EXPECT_EQ(pd.size(), 160u);
  EXPECT_LT(path.size(), pd.size() - 4);
  expectSameSearch(pd, path);
  // Coast turning right (where the line was) for lost_grace, spin right, give up.
  EXPECT_EQ(pd[0].state, kLost);
  EXPECT_EQ(pd[0].angular, -0.4);
  EXPECT_EQ(pd[7].state, kLost);  // 1 s
  EXPECT_EQ(pd[8].state, kSearching);
  EXPECT_EQ(pd[8].angular, -0.6);
  EXPECT_EQ(pd[103].state, kSearching);  // 13 s
  EXPECT_EQ(pd[104].state, kGaveUp);
  EXPECT_EQ(path.back().state, kGaveUp);
}

}  // namespace
}  // namespace follow_bot
