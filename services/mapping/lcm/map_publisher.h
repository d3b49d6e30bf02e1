#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "cairn/lcmt_tile_resend_request.hpp"

#include "services/mapping/lcm/terrain_publisher.h"
#include "services/mapping/mapper_core.h"
#include "services/runtime/node.h"
#include "services/runtime/tiler.h"

/// @file
/// MapPublisher: everything cairn-mapper sends about its layers, each layer at its own period
/// (MapperLayer::schedule), with map_name as configured:
/// - the terrain layer: <robot>.MAP.TILES / .MAP.MANIFEST, only the tiles that changed, the fast
///   layers (elevation, slope, step, roughness, cost/<profile>) at its publish period with every
///   manifest each time (receivers read them as "the layer is current"), the base statistics and
///   ditches at its slow period, and <robot>.MAP.OBSTACLES, the obstacle registry;
/// - the OctoMap layer: <robot>.MAP.OCTOMAP, the tree's .bt stream in chunks, when it changed;
/// - every other layer, generically: its GridOutputs when its version changed, occupancy grids as
///   int8 tiles on <robot>.MAP.OCCUPANCY and float grids on <robot>.MAP.TILES, then every
///   manifest of the layer on <robot>.MAP.MANIFEST.
/// Runs on the mapper's worker thread.

namespace cairn::mapping {

class MapPublisher {
 public:
  struct Options {
    std::string robot;
    std::string map_name;
    int tiles_per_burst{8};
    double burst_pause_ms{1.0};
    /// Layer versions start above this (runtime::LayerTiler::StartVersionBase in a live mapper).
    int64_t version_base{0};
  };
  /// Locks a layer that runs on a thread of its own (an empty lock for the others).
  using LayerLock = std::function<std::unique_lock<std::mutex>(const MapperLayer&)>;

  /// `node` and `core` must outlive the publisher.
  MapPublisher(runtime::Node& node, MapperCore& core, Options options, LayerLock lock);

  /// Publishes every layer whose period is due (all of them with `force`). `map_version` stamps
  /// the registry (the revolutions mapped).
  void PublishDue(bool force, int64_t map_version);
  /// The layers whose manifests the last PublishDue sent, in the order sent (a retired layer's
  /// empty manifest is not counted): with `force`, every layer the mapper has.
  const std::vector<std::string>& announced() const { return announced_; }
  /// Answers a resend request for a terrain layer or another layer's grid.
  void Resend(const cairn::lcmt_tile_resend_request& request);
  /// After the core was reset: every terrain layer starts afresh; with `send`, their empty
  /// manifests go out (receivers drop what they hold).
  void AfterReset(bool send);
  /// A removed profile's cost layer: its (empty) manifest goes out at the next publication.
  void RetireLayer(const std::string& layer);
  /// A profile added again: its cost layer is no longer retired.
  void UnretireLayer(const std::string& layer);

 private:
  using Clock = std::chrono::steady_clock;
  struct LayerState {
    MapperLayer* layer{nullptr};
    Clock::time_point next;
    int64_t published_version{-1};
  };

  void PublishTerrain(const std::vector<std::string>& layers, bool force);
  void PublishRegistry(bool force, int64_t map_version);
  void PublishOctomap(LayerState* state, bool force);
  void PublishGrids(LayerState* state, bool force);
  std::vector<std::string> FastLayers() const;
  static std::vector<std::string> SlowLayers();
  template <typename Msg>
  void Send(const std::string& stream, const std::vector<Msg>& messages);

  runtime::Node& node_;
  MapperCore& core_;
  int64_t last_map_version_{0};    ///< map_version of the last PublishDue
  int64_t last_data_version_{-1};  ///< map_version (revolutions) at the last check
  Clock::time_point last_data_;    ///< when map_version last changed
  bool announcing_{true};
  Options options_;
  LayerLock lock_;
  std::vector<LayerState> layers_;
  TerrainMapperLayer* terrain_{nullptr};
  TerrainPublisher terrain_publisher_;
  runtime::LayerTiler grid_tiler_;
  std::vector<std::string> retired_layers_;
  std::vector<std::string> announced_;  ///< see announced()
  std::string last_registry_bytes_;
  Clock::time_point next_slow_, next_registry_;
  int64_t octomap_chunk_version_{0};
};

}  // namespace cairn::mapping
