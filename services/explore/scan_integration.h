#pragma once

#include <cstdint>

#include "services/explore/info_map.h"
#include "services/explore/scan_features.h"
#include "services/explore/scan_mesh.h"

/// @file
/// One ordered turret scan into the information map: the mesh, the per-point features and the
/// points on the map (seed 002 §3.1–3.3). The explorer's mission (nbv_mission.h) and the mapper's
/// information-map layer (services/mapping/explore_mapper_layer.h) run this same step, so the
/// same sweeps give both the same map.

namespace cairn::explore {

struct ScanIntegrationParams {
  MeshParams mesh;
  ScanAnalysisParams analysis;
  /// Cells under the scan's accepted triangles that no point fell in are explored too
  /// (FillSurfaceCells): the far ground rings leave such cells between them.
  bool fill_surface{true};
};

struct IntegratedScan {
  ScanFeatures features;    ///< per point, and the scan's interest zones
  int64_t points_used{0};   ///< points that fell on the information map
  double mesh_ms{0.0};      ///< triangulation (wall clock)
  double analysis_ms{0.0};  ///< per-point features and zones
  double map_ms{0.0};       ///< onto the information map
};

/// Meshes `scan` (into `mesh`, reused between scans), scores its points and adds them to `map`
/// as seen from the scan's sensor origin.
IntegratedScan IntegrateScan(const OrderedScan& scan, const ScanIntegrationParams& params,
                             InfoMap* map, ScanMesh* mesh);

}  // namespace cairn::explore
