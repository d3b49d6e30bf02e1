#pragma once

#include <string>

/// @file
/// Every LCM channel name of the product, in one place. Per-robot channels are
/// "<robot>.<STREAM>" (rover1.LIDAR); fleet channels have no prefix.

namespace cairn::channels {

// Fleet channels.
inline constexpr char kHealth[] = "HEALTH";
inline constexpr char kSimClock[] = "SIM.CLOCK";
inline constexpr char kSimControl[] = "SIM.CONTROL";
inline constexpr char kSimControlReply[] = "SIM.CONTROL_REPLY";
inline constexpr char kMapstoreRequest[] = "MAPSTORE.REQUEST";
inline constexpr char kMapstoreReply[] = "MAPSTORE.REPLY";
inline constexpr char kMapstoreTiles[] = "MAPSTORE.TILES";
inline constexpr char kMapstoreTileBatches[] = "MAPSTORE.TILE_BATCHES";  // compressed reply tiles
inline constexpr char kMapstoreTileResend[] = "MAPSTORE.TILE_RESEND";
inline constexpr char kMapstoreManifest[] = "MAPSTORE.MANIFEST";  // manifests of reply layers
inline constexpr char kMapstoreOctomap[] = "MAPSTORE.OCTOMAP";    // OctoMap chunks of replies
// A push save: the client sends its layers, obstacles and OctoMap here before OP_SAVE, and
// answers the store's resend requests for tiles it missed.
inline constexpr char kMapstorePushTiles[] = "MAPSTORE.PUSH.TILES";  // float tiles (resends)
inline constexpr char kMapstorePushTileBatches[] = "MAPSTORE.PUSH.TILE_BATCHES";  // compressed
inline constexpr char kMapstorePushManifest[] = "MAPSTORE.PUSH.MANIFEST";
inline constexpr char kMapstorePushObstacles[] = "MAPSTORE.PUSH.OBSTACLES";
inline constexpr char kMapstorePushOctomap[] = "MAPSTORE.PUSH.OCTOMAP";
inline constexpr char kMapstorePushTileResend[] = "MAPSTORE.PUSH.TILE_RESEND";

// Per-robot stream suffixes.
inline constexpr char kLidar[] = "LIDAR";  // lidar slices as points (lcmt_point_cloud_slice)
inline constexpr char kLidarRanges[] = "LIDAR_RANGES";  // as ranges (lcmt_lidar_ranges)
inline constexpr char kScan[] = "SCAN";
inline constexpr char kTurretScan[] = "TURRET_SCAN";
inline constexpr char kOdom[] = "ODOM";
inline constexpr char kPose[] = "POSE";  // ground truth
inline constexpr char kImu[] = "IMU";
inline constexpr char kSonar[] = "SONAR";
inline constexpr char kSonarDetections[] = "SONAR_DETECTIONS";  // cairn-mapper: per-ping obstacles
inline constexpr char kCmdVel[] = "CMD_VEL";
inline constexpr char kBodyVelocity[] = "BODY_VELOCITY_REQ";  // AUV body-velocity requests
inline constexpr char kGoal[] = "GOAL";
inline constexpr char kPath[] = "PATH";
inline constexpr char kNavStatus[] = "NAV_STATUS";
inline constexpr char kExploreStatus[] = "EXPLORE_STATUS";   // cairn-explorer progress
inline constexpr char kMapTiles[] = "MAP.TILES";             // grid-map layer tiles
inline constexpr char kMapManifest[] = "MAP.MANIFEST";       // layer versions and tile checksums
inline constexpr char kMapTileResend[] = "MAP.TILE_RESEND";  // receivers ask for missed tiles
inline constexpr char kMapOccupancy[] = "MAP.OCCUPANCY";     // 2-D occupancy tiles
inline constexpr char kMapOctomap[] = "MAP.OCTOMAP";
inline constexpr char kMapObstacles[] = "MAP.OBSTACLES";
inline constexpr char kMapControl[] = "MAP.CONTROL";  // mapper requests (clear layer, reload)
inline constexpr char kMapControlReply[] = "MAP.CONTROL_REPLY";

/// "<robot>.<stream>".
inline std::string ForRobot(const std::string& robot, const char* stream) {
  return robot + "." + stream;
}

}  // namespace cairn::channels
