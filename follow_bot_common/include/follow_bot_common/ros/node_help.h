// What a node's `--help` prints: its usage, what it does, its topics and where its parameters are
// documented. Printed before ros::init, so it needs no master.
#pragma once

#include <algorithm>
#include <cstring>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

#include <ros/package.h>

namespace follow_bot_common {

struct TopicHelp {
  std::string direction;  // in, out or service
  std::string name;       // as the node resolves it: relative, or ~private
  std::string type;
  std::string note;
};

struct NodeHelp {
  std::string summary;  // one sentence: what the node does
  std::vector<TopicHelp> topics;
};

// True when the command line asks for help (-h or --help).
inline bool helpAsked(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "-h") == 0 || std::strcmp(argv[i], "--help") == 0) return true;
  }
  return false;
}

// Prints `rosrun package node`'s usage, `help`, and the node's manual, doc/<node>.md of its
// package, which documents every ~param (found through rospack, so it is the source tree's in a
// devel space and the installed copy otherwise; add_behaviour_node installs it). Returns the exit
// code, 0.
inline int printHelp(const std::string& package, const std::string& node, const NodeHelp& help) {
  std::size_t name_width = 0, type_width = 0;
  for (const TopicHelp& topic : help.topics) {
    name_width = std::max(name_width, topic.name.size());
    type_width = std::max(type_width, topic.type.size());
  }
  std::cout << "usage: " << node
            << " [-h] [NAME:=NEW_NAME ...] [_PARAM:=VALUE ...] [__name:=NODE] [__ns:=NAMESPACE]\n"
            << "(rosrun " << package << " " << node << " ...)\n\n"
            << help.summary << "\n\ntopics (relative to the node's namespace, ~: its private one; "
            << "NAME:=NEW_NAME renames one):\n";
  for (const TopicHelp& topic : help.topics) {
    std::cout << "  " << std::left << std::setw(8) << topic.direction
              << std::setw(static_cast<int>(name_width) + 2) << topic.name
              << std::setw(static_cast<int>(type_width) + 2) << topic.type << topic.note << "\n";
  }
  const std::string package_path = ros::package::getPath(package);
  std::cout << "\nparameters (~PARAM, set with _PARAM:=VALUE; each with its type, default, range "
               "and unit):\n  "
            << (package_path.empty() ? package + "'s " : package_path + "/") << "doc/" << node
            << ".md\n"
            << "  A ~param the node does not have is warned about at start-up, with the nearest "
               "name it has;\n  _strict_params:=true makes that an error.\n"
            << "\nCtrl-C or SIGTERM ends it at any time, also while it waits for the ROS master.\n";
  return 0;
}

}  // namespace follow_bot_common
