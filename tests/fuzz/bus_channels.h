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
          ch::ForRobot(kRobot, ch::kMapTileResend), ch::kMapstoreReply,
          ch::ForRobot(kRobot, ch::kLidarRanges)};  // last: earlier seeds keep their channels
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

/// cairn-launch reads HEALTH and meters every channel (readiness by rate).
inline std::vector<std::string> LauncherChannels() {
  namespace ch = channels;
  return {ch::kHealth, ch::ForRobot(kRobot, ch::kPose), ch::ForRobot(kRobot, ch::kLidar),
          ch::kSimClock, ch::ForRobot(kRobot, ch::kLidarRanges)};
}

/// cairn-explorer in every mode: reactive (scans, poses), frontier (the occupancy layer, the
/// navigator's status), next-best-view (turret lines, the simulator's control replies).
inline std::vector<std::string> ExplorerChannels() {
  namespace ch = channels;
  return {ch::ForRobot(kRobot, ch::kScan),         ch::ForRobot(kRobot, ch::kPose),
          ch::ForRobot(kRobot, ch::kNavStatus),    ch::ForRobot(kRobot, ch::kTurretScan),
          ch::kSimControlReply,                    ch::ForRobot(kRobot, ch::kMapOccupancy),
          ch::ForRobot(kRobot, ch::kMapManifest),  ch::kSimClock};
}

/// The map store's client (cairn-mission, cairn-explorer's save, cairn-map): replies, reply
/// layers (tiles, batches, manifests, OctoMap chunks) and the store's resend requests of a push.
inline std::vector<std::string> MapstoreClientChannels() {
  namespace ch = channels;
  return {ch::kMapstoreReply,    ch::kMapstoreTiles,   ch::kMapstoreTileBatches,
          ch::kMapstoreManifest, ch::kMapstoreOctomap, ch::kMapstorePushTileResend};
}

/// cairn-sim: the robot's velocity commands and body-velocity requests, SIM.CONTROL.
inline std::vector<std::string> SimChannels() {
  namespace ch = channels;
  return {ch::ForRobot(kRobot, ch::kCmdVel), ch::ForRobot(kRobot, ch::kBodyVelocity),
          ch::kSimControl};
}

/// The channel list of a bus target by name; empty for another target.
inline std::vector<std::string> BusChannels(const std::string& target) {
  if (target == "bus_navigator_map") return NavigatorMapChannels();
  if (target == "bus_mapper") return MapperChannels();
  if (target == "bus_mapstore") return MapstoreChannels();
  if (target == "bus_launcher") return LauncherChannels();
  if (target == "bus_explorer") return ExplorerChannels();
  if (target == "bus_mapstore_client") return MapstoreClientChannels();
  if (target == "bus_sim") return SimChannels();
  return {};
}

}  // namespace cairn::fuzz
