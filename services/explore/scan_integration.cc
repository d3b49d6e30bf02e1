#include "services/explore/scan_integration.h"

#include <chrono>
#include <cmath>
#include <vector>

namespace cairn::explore {
namespace {

double MsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

IntegratedScan IntegrateScan(const OrderedScan& scan, const ScanIntegrationParams& params,
                             InfoMap* map, ScanMesh* mesh) {
  IntegratedScan out;
  auto t0 = std::chrono::steady_clock::now();
  BuildScanMesh(scan, params.mesh, mesh);
  out.mesh_ms = MsSince(t0);
  t0 = std::chrono::steady_clock::now();
  out.features = AnalyseScan(scan, *mesh, params.analysis);
  out.analysis_ms = MsSince(t0);
  t0 = std::chrono::steady_clock::now();
  const ScanFeatures& features = out.features;
  std::vector<ScoredPoint> scored(scan.points_m.size());
  std::vector<uint8_t> valid(scan.points_m.size(), 0);
  std::vector<ScoredPoint> points;
  points.reserve(scan.points_m.size());
  for (size_t i = 0; i < scan.points_m.size(); ++i) {
    if (!std::isfinite(features.navigability[i])) continue;
    ScoredPoint& p = scored[i];
    p.position_m = scan.points_m[i];
    p.normal = mesh->normals[i].allFinite() ? mesh->normals[i] : Eigen::Vector3f::Zero();
    p.navigability = features.navigability[i];
    p.obstacle = std::isfinite(features.obstacle[i]) ? features.obstacle[i] : 0.f;
    p.quality = std::isfinite(features.quality[i]) ? features.quality[i] : 0.f;
    valid[i] = p.position_m.allFinite();
    points.push_back(p);
  }
  if (params.fill_surface) {
    const std::vector<ScoredPoint> filled = FillSurfaceCells(*map, scored, valid, mesh->triangles);
    points.insert(points.end(), filled.begin(), filled.end());
  }
  out.points_used = map->AddPoints(points, scan.sensor_origin_m.z());
  out.map_ms = MsSince(t0);
  return out;
}

}  // namespace cairn::explore
