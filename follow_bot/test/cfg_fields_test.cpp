// The cores' field lists against the behaviours' .cfg files (through dynamic_reconfigure's own
// generated configs): every parameter a list names exists with a type that fits, its default is
// the field's default, and a changed value reaches the field (scaled where the list says so).
#include <gtest/gtest.h>

#include <set>
#include <string>
#include <type_traits>

#include <boost/any.hpp>

#include "follow_bot/BeaconChaserConfig.h"
#include "follow_bot/FollowerConfig.h"
#include "follow_bot/PanoramaConfig.h"
#include "follow_bot/ParkerConfig.h"
#include "follow_bot/beacon_controller.h"
#include "follow_bot/colour_blobs.h"
#include "follow_bot/common.h"
#include "follow_bot/line_detector.h"
#include "follow_bot/panorama_session.h"
#include "follow_bot/parking_servo.h"
#include "follow_bot/sign_detector.h"
#include "follow_bot/steering_law.h"
#include "follow_bot/tag_detector.h"
#include "follow_bot_common/ros/config_mapping.h"
#include "image_converter/ImageConverterConfig.h"
#include "image_converter/MatchingConfig.h"
#include "image_converter/feature_matching.h"
#include "image_converter/overlay.h"

namespace follow_bot {
namespace {

// `name`'s value in `config`, read through dynamic_reconfigure's description of it.
template <typename ConfigT>
boost::any parameterValue(const ConfigT& config, const std::string& name) {
  for (const auto& description : ConfigT::__getParamDescriptions__()) {
    if (description->name != name) continue;
    boost::any value;
    description->getValue(config, value);
    return value;
  }
  ADD_FAILURE() << name << " is not in the .cfg";
  return {};
}

template <typename T>
T expectedValue(const boost::any& value, double scale) {
  if constexpr (std::is_floating_point_v<T>) {
    if (const int* whole = boost::any_cast<int>(&value)) return *whole * scale;
    return boost::any_cast<double>(value) * scale;
  } else {
    return boost::any_cast<T>(value);
  }
}

// Every cfgField of Struct, set from `config`, holds the parameter's value; the other fields
// keep `before`'s.
template <typename Struct, typename ConfigT>
void expectSetFrom(const ConfigT& config, const Struct& before = Struct()) {
  Struct mapped = before;
  ASSERT_NO_THROW(assignFromConfig(mapped, config));
  forEachField<Struct>([&](const auto& field) {
    SCOPED_TRACE(field.name);
    using T = std::decay_t<decltype(mapped.*field.member)>;
    if (field.cfg_param == nullptr) {
      EXPECT_EQ(mapped.*field.member, before.*field.member);
      return;
    }
    const T expected = expectedValue<T>(parameterValue(config, field.cfg_param), field.cfg_scale);
    if constexpr (std::is_floating_point_v<T>) {
      EXPECT_DOUBLE_EQ(mapped.*field.member, expected) << field.cfg_param;
    } else {
      EXPECT_EQ(mapped.*field.member, expected) << field.cfg_param;
    }
  });
}

// Each core's own defaults are the .cfg's, and the .cfg's largest values reach every field.
template <typename ConfigT, typename... Structs>
void expectFieldsFollowTheCfg() {
  const auto follow = [](auto core) {
    using Struct = decltype(core);
    {
      SCOPED_TRACE("the .cfg's defaults give the core's defaults");
      expectSetFrom<Struct>(ConfigT::__getDefault__());
    }
    {
      SCOPED_TRACE("the .cfg's maxima reach the fields");
      expectSetFrom<Struct>(ConfigT::__getMax__());
    }
  };
  (follow(Structs()), ...);
}

TEST(CfgFields, EachCoreFollowsItsCfg) {
  expectFieldsFollowTheCfg<FollowerConfig, LineDetectorConfig, SteeringConfig, PdConfig,
                           LineSearchConfig, PathConfig>();
  expectFieldsFollowTheCfg<BeaconChaserConfig, BeaconControllerConfig, ColourBlobConfig>();
  expectFieldsFollowTheCfg<ParkerConfig, TagDetectorConfig, ParkingServoConfig,
                           SignDetectorConfig>();
  expectFieldsFollowTheCfg<PanoramaConfig, PanoramaCaptureConfig, PanoramaSessionConfig>();
  expectFieldsFollowTheCfg<image_converter::ImageConverterConfig, image_converter::OverlayConfig>();
  expectFieldsFollowTheCfg<image_converter::MatchingConfig, image_converter::MatchOptions>();
}

// The .cfg's parameters that the cores' field lists name, with `others`.
template <typename... Structs>
std::set<std::string> parametersSet(std::set<std::string> others) {
  const auto add = [&](const auto& field) {
    if (field.cfg_param != nullptr) others.insert(field.cfg_param);
  };
  (forEachField<Structs>(add), ...);
  return others;
}

template <typename ConfigT>
std::set<std::string> cfgParameters() {
  std::set<std::string> names;
  for (const auto& description : ConfigT::__getParamDescriptions__()) {
    names.insert(description->name);
  }
  return names;
}

// Every .cfg parameter sets a field of a core through its list, or is one of those that the
// settings mapping (src/nodelets/settings.cpp) or a nodelet reads itself: choices, a colour
// box, a band, and the nodelets' own switches. A new parameter in neither is never applied.
TEST(CfgFields, EveryParameterIsApplied) {
  EXPECT_EQ(
      (parametersSet<LineDetectorConfig, SteeringConfig, PdConfig, LineSearchConfig, PathConfig>(
          {"mode", "h_min", "h_max", "s_min", "s_max", "v_min", "v_max", "band_distance",
           "band_rows", "look_ahead_distance", "estimate_latency"})),
      cfgParameters<FollowerConfig>());
  EXPECT_EQ((parametersSet<BeaconControllerConfig, ColourBlobConfig>(
                {"mode", "sensitivity", "s_min", "v_min", "roundness_tolerance", "ball_radius",
                 "ball_size_tolerance", "follow_colour", "stop_colour", "target_colour"})),
            cfgParameters<BeaconChaserConfig>());
  EXPECT_EQ((parametersSet<TagDetectorConfig, SignDetectorConfig, ParkingServoConfig>(
                {"target", "publish_tf", "marker_frame"})),
            cfgParameters<ParkerConfig>());
  EXPECT_EQ((parametersSet<PanoramaCaptureConfig, PanoramaSessionConfig>({"stitch_method"})),
            cfgParameters<PanoramaConfig>());
  EXPECT_EQ(parametersSet<image_converter::OverlayConfig>({"display", "image_transport"}),
            cfgParameters<image_converter::ImageConverterConfig>());
  EXPECT_EQ(parametersSet<image_converter::MatchOptions>({"detector"}),
            cfgParameters<image_converter::MatchingConfig>());
}

// A field list naming a parameter the .cfg lacks is a bug, said at once.
struct Misnamed {
  double gain = 1.0;
  static constexpr auto fields() {
    return std::make_tuple(cfgField("gain", &Misnamed::gain, {}, "no_such_parameter"));
  }
};

TEST(CfgFields, AParameterTheCfgLacksThrows) {
  Misnamed misnamed;
  EXPECT_THROW(assignFromConfig(misnamed, FollowerConfig::__getDefault__()), std::logic_error);
}

}  // namespace
}  // namespace follow_bot
