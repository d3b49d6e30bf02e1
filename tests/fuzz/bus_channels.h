#pragma once

#include <string>
#include <vector>

#include "common/channels.h"

/// @file
/// The channels each bus fuzz target feeds (a frame's first byte picks one), shared with the
/// tool that cuts their seeds from recorded logs. The robot is the demo's, "p3at" (a
/// pioneer3at), so messages recorded from scripts/demo reach the handlers as they would live.

namespace cairn::fuzz {

inline constexpr char kRobot[] = "p3at";

inline std::vector<std::string> NavigatorMapChannels() {
  namespace ch = channels;
  return {ch::ForRobot(kRobot, ch::kMapTiles), ch::ForRobot(kRobot, ch::kMapManifest),
          ch::ForRobot(kRobot, ch::kMapOccupancy)};
}

inline std::vector<std::string> MapperChannels() {
  namespace ch = channels;
  return {ch::ForRobot(kRobot, ch::kLidar),         ch::ForRobot(kRobot, ch::kScan),
          ch::ForRobot(kRobot, ch::kPose),          ch::ForRobot(kRobot, ch::kOdom),
          ch::ForRobot(kRobot, ch::kImu),           ch::ForRobot(kRobot, ch::kMapControl),
          ch::ForRobot(kRobot, ch::kMapTileResend), ch::kMapstoreReply};
}

inline std::vector<std::string> MapstoreChannels() {
  namespace ch = channels;
  return {ch::kMapstoreRequest,
          ch::kMapstorePushTiles,
          ch::kMapstorePushTileBatches,
          ch::kMapstorePushManifest,
          ch::kMapstorePushObstacles,
          ch::kMapstorePushOctomap,
          ch::kMapstoreTileResend,
          ch::ForRobot(kRobot, ch::kMapTiles),
          ch::ForRobot(kRobot, ch::kMapManifest),
          ch::ForRobot(kRobot, ch::kMapObstacles),
          ch::ForRobot(kRobot, ch::kMapOctomap)};
}

/// The channel list of a bus target by name; empty for another target.
inline std::vector<std::string> BusChannels(const std::string& target) {
  if (target == "bus_navigator_map") return NavigatorMapChannels();
  if (target == "bus_mapper") return MapperChannels();
  if (target == "bus_mapstore") return MapstoreChannels();
  return {};
}

}  // namespace cairn::fuzz
