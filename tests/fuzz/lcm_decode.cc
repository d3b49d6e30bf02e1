// Every lcmt_* type: the first byte picks a type (tests/fuzz/lcm_types.h), the rest is decoded
// as a message of it (with the bounded decoders of cmake/BoundLcmDecode.cmake) and, when it
// decodes, encoded again and converted to core terms the way its receivers do. Nothing may
// crash, throw or allocate beyond the input's size.

#include <cstdint>
#include <vector>

#include "mapstore/lcm/mapstore_conversions.h"
#include "mapstore/lcm/tile_wire.h"
#include "services/runtime/conversions.h"
#include "services/runtime/tile_conversions.h"
#include "tests/fuzz/lcm_types.h"

namespace {

using namespace cairn;

// What a receiver does with a decoded message, by type: most are read field by field (decoding
// is the risk); those with a conversion to core terms go through it.
template <typename Msg>
void Handle(const Msg&) {}
template <>
void Handle(const lcmt_grid_manifest& m) {
  (void)runtime::FromLcm(m);
}
template <>
void Handle(const lcmt_grid_tile& tile) {
  (void)runtime::CheckFloatTile(tile);
  std::vector<float> cells;
  (void)mapstore::DecodeTileCells(tile, &cells);
}
template <>
void Handle(const lcmt_grid_tile_batch& batch) {
  std::vector<std::vector<float>> cells;
  std::vector<char> ok;
  mapstore::DecodeTiles(batch.tiles, batch.map_name, 1, &cells, &ok);
}
template <>
void Handle(const lcmt_laser_scan& m) {
  (void)runtime::FromLcm(m);
}
template <>
void Handle(const lcmt_obstacle& m) {
  (void)runtime::FromLcm(m);
}
template <>
void Handle(const lcmt_obstacle_registry& m) {
  (void)runtime::FromLcm(m);
}
template <>
void Handle(const lcmt_occupancy_tile& tile) {
  std::vector<float> cells;
  (void)runtime::CheckOccupancyTile(tile, &cells);
}
template <>
void Handle(const lcmt_map_control_reply& m) {
  (void)mapstore::FromLcm(m);
}
template <>
void Handle(const lcmt_octomap& m) {
  (void)mapstore::FromLcm(m);
}
template <>
void Handle(const lcmt_odometry& m) {
  (void)runtime::FromLcm(m);
}
template <>
void Handle(const lcmt_place& m) {
  (void)mapstore::FromLcm(m);
}
template <>
void Handle(const lcmt_point_cloud_slice& m) {
  (void)runtime::FromLcm(m);
}
template <>
void Handle(const lcmt_lidar_ranges& m) {
  (void)runtime::FromLcm(m);
}
template <>
void Handle(const lcmt_pose& m) {
  (void)runtime::FromLcm(m);
}
template <>
void Handle(const lcmt_robot_profile& m) {
  (void)runtime::FromLcm(m);
}
template <>
void Handle(const lcmt_tile_resend_request& m) {
  (void)runtime::FromLcm(m);
}

template <typename Msg>
void Run(const uint8_t* data, size_t size) {
  Msg msg;
  if (msg.decode(data, 0, static_cast<int>(size)) < 0) return;
  // What decoded encodes again.
  std::vector<uint8_t> again(static_cast<size_t>(msg.getEncodedSize()));
  if (msg.encode(again.data(), 0, static_cast<int>(again.size())) < 0) std::abort();
  Handle(msg);
}

using Runner = void (*)(const uint8_t*, size_t);
#define CAIRN_RUNNER(T) &Run<T>,
constexpr Runner kRunners[] = {CAIRN_FUZZ_LCM_TYPES(CAIRN_RUNNER)};
#undef CAIRN_RUNNER

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  kRunners[data[0] % (sizeof(kRunners) / sizeof(kRunners[0]))](data + 1, size - 1);
  return 0;
}
