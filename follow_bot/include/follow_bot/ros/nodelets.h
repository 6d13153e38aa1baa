// Factories for the behaviour nodelets, so the thin nodes can run them without pluginlib.
#pragma once

#include <memory>

#include <nodelet/nodelet.h>

namespace follow_bot {

std::unique_ptr<nodelet::Nodelet> makeFollowerNodelet();
std::unique_ptr<nodelet::Nodelet> makeBeaconChaserNodelet();
std::unique_ptr<nodelet::Nodelet> makeParkerNodelet();
std::unique_ptr<nodelet::Nodelet> makePanoramaNodelet();

}  // namespace follow_bot
