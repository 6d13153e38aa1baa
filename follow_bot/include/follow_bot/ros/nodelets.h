// The behaviour nodelets' factories and --help, so the generated nodes (add_behaviour_node in
// CMakeLists.txt) run them without pluginlib.
#pragma once

#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "follow_bot/common.h"
#include "follow_bot_common/ros/node_help.h"

namespace follow_bot {

std::unique_ptr<nodelet::Nodelet> makeFollowerNodelet();
std::unique_ptr<nodelet::Nodelet> makeBeaconChaserNodelet();
std::unique_ptr<nodelet::Nodelet> makeParkerNodelet();
std::unique_ptr<nodelet::Nodelet> makePanoramaNodelet();

// What each node's --help says it does and which topics it has (with its nodelet's code).
NodeHelp followerHelp();
NodeHelp beaconChaserHelp();
NodeHelp parkerHelp();
NodeHelp panoramaHelp();

}  // namespace follow_bot

// Defines follow_bot::make<Class>() and exports follow_bot::Class as a nodelet plugin; at global
// scope after the class.
#define FOLLOW_BOT_EXPORT_NODELET(Class)                        \
  std::unique_ptr<nodelet::Nodelet> follow_bot::make##Class() { \
    return std::make_unique<follow_bot::Class>();               \
  }                                                             \
  PLUGINLIB_EXPORT_CLASS(follow_bot::Class, nodelet::Nodelet)
