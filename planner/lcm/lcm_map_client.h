#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_occupancy_tile.hpp"

#include "planner/cost_map.h"
#include "planner/map_source.h"
#include "planner/occupancy_cost.h"
#include "services/runtime/node.h"
#include "services/runtime/tiler.h"

/// @file
/// LcmMapClient: a MapSource that rebuilds one layer from a mapper's tiles and manifests
/// (<robot>.MAP.MANIFEST), asks for missing tiles on <robot>.MAP.TILE_RESEND, and turns each
/// complete layer version into a CostMap. The layer is either a cost layer ("cost/<profile>",
/// float tiles on <robot>.MAP.TILES) or a 2-D occupancy layer (the dynamic map server's
/// "final", int8 tiles on <robot>.MAP.OCCUPANCY) converted to cost by OccupancyToCostLayer.

namespace cairn::planner {

struct LcmMapClientParams {
  std::string robot;
  std::string layer;  ///< "cost/<profile>" (kCost), or "final", "long_term"... (kOccupancy)
  MapEncoding encoding{MapEncoding::kCost};
  OccupancyCostParams occupancy;  ///< kOccupancy: the occupancy-to-cost thresholds
  std::string map_name;           ///< accept only this map name ("" = any)
  std::string requester{"cairn-navigator"};
  double resend_interval_s{0.5};
  /// Build a snapshot from an incomplete version after this long; the cells of tiles that are
  /// still missing count as lethal (their content is unknown to us, not unexplored).
  double incomplete_timeout_s{1.0};
};

class LcmMapClient : public MapSource {
 public:
  /// Subscribes on `node` (which must outlive the client).
  /// @throws std::invalid_argument for an invalid footprint, cost-map or occupancy params.
  LcmMapClient(runtime::Node& node, LcmMapClientParams params,
               std::vector<common::Vector2> footprint_m, CostMapParams cost_params);
  LcmMapClient(const LcmMapClient&) = delete;
  LcmMapClient& operator=(const LcmMapClient&) = delete;

  std::shared_ptr<const CostMap> Latest() const override;
  int64_t last_heard_utime() const override;

  /// Handlers (public for tests that drive the client without a bus).
  void OnTile(const cairn::lcmt_grid_tile& tile);
  void OnTile(const cairn::lcmt_occupancy_tile& tile);
  void OnManifest(const cairn::lcmt_grid_manifest& manifest);
  /// Sends resend requests and builds overdue incomplete snapshots; call periodically.
  void Poll();

  int64_t snapshots() const { return snapshots_; }

 private:
  bool Accepts(const std::string& robot, const std::string& map_name,
               const std::string& layer) const;
  template <typename TileMsg>
  void OnTileImpl(const TileMsg& tile);
  void MaybeBuild(bool allow_incomplete);

  runtime::Node& node_;
  LcmMapClientParams params_;
  std::vector<common::Vector2> footprint_m_;
  CostMapParams cost_params_;
  runtime::LayerAssembler assembler_;
  mutable std::mutex mutex_;
  std::shared_ptr<const CostMap> latest_;
  int64_t heard_utime_{0};
  int64_t built_version_{-1};
  bool built_incomplete_{false};    // the version in use was built with missing tiles
  int64_t pending_since_utime_{0};  // when the newest unbuilt version was announced
  int64_t last_resend_utime_{0};
  int64_t snapshots_{0};
  int tile_size_{0};  // of the newest manifest
};

}  // namespace cairn::planner
