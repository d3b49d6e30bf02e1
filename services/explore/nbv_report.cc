#include "services/explore/nbv_report.h"

#include <cstdio>
#include <limits>

#include "mapstore/io/files.h"
#include "mapstore/io/png.h"

namespace cairn::explore {

std::string NbvSummaryTable(const NbvMission& mission, const std::string& preset) {
  std::string out;
  char line[256];
  const auto& views = mission.view_points();
  const double coverage = views.empty() ? 0.0 : views.back().coverage;
  const double quality = views.empty() ? 0.0 : views.back().mean_quality;
  std::snprintf(line, sizeof(line),
                "next-best-view (%s): %d scans, %.1f m driven, coverage %.1f %%, mean quality "
                "%.3f, %d goals (%d reached, %d failed)\n",
                preset.c_str(), mission.scans(), mission.distance_m(), 100.0 * coverage, quality,
                mission.goals_sent(), mission.goals_reached(), mission.goals_failed());
  out += line;
  if (!mission.end_reason().empty()) out += "ended: " + mission.end_reason() + "\n";
  out +=
      "scan      x m      y m   time s   points  coverage %  quality  zones   mesh ms  "
      "analysis ms  decision ms\n";
  for (size_t i = 0; i < views.size(); ++i) {
    const ViewPoint& v = views[i];
    std::snprintf(
        line, sizeof(line), "%4zu %8.2f %8.2f %8.1f %8lld %11.1f %8.3f %6d %9.1f %12.1f %12.1f\n",
        i + 1, v.position_m.x(), v.position_m.y(), v.time_s, static_cast<long long>(v.points_used),
        100.0 * v.coverage, v.mean_quality, v.zones, v.mesh_ms, v.analysis_ms, v.decision_ms);
    out += line;
  }
  return out;
}

std::string NbvPathCsv(const NbvMission& mission) {
  const InfoMap& map = mission.info_map();
  std::string out = "kind,index,x_m,y_m,level,ground_z_m,cnc_when_chosen,cnc_final\n";
  char line[192];
  auto final_cnc = [&](int64_t node) {
    return map.Explored(node) ? map.Navigability(node) : std::numeric_limits<float>::quiet_NaN();
  };
  const auto& views = mission.view_points();
  for (size_t i = 0; i < views.size(); ++i) {
    const ViewPoint& v = views[i];
    const bool on_map = v.node >= 0 && v.node < map.num_nodes();
    // The surface it stood on, in the final map: a later scan may have found a lower one under
    // it (the road under a deck) and moved it to the upper level.
    const int64_t now = on_map ? map.NearestLevel(map.NodeCell(v.node), v.ground_z_m) : -1;
    std::snprintf(line, sizeof(line), "view,%zu,%.3f,%.3f,%d,%.3f,nan,%.4f\n", i + 1,
                  v.position_m.x(), v.position_m.y(), on_map ? map.NodeLevel(now) : -1,
                  v.ground_z_m, on_map ? final_cnc(now) : std::numeric_limits<float>::quiet_NaN());
    out += line;
  }
  const auto& legs = mission.legs();
  for (size_t l = 0; l < legs.size(); ++l) {
    for (size_t k = 0; k < legs[l].nodes.size(); ++k) {
      const int64_t node = legs[l].nodes[k];
      if (node < 0 || node >= map.num_nodes()) continue;
      const common::Vector2 xy = map.geometry().CenterOf(map.Cell(node));
      // The same surface in the final map: the cell's level nearest the ground it had then.
      const int64_t now = map.NearestLevel(map.NodeCell(node), legs[l].ground_z_m[k]);
      std::snprintf(line, sizeof(line), "path,%zu,%.3f,%.3f,%d,%.3f,%.4f,%.4f\n", l + 1, xy.x(),
                    xy.y(), map.NodeLevel(now), legs[l].ground_z_m[k], legs[l].cnc_when_chosen[k],
                    final_cnc(now));
      out += line;
    }
  }
  return out;
}

common::Result<std::vector<std::string>> WriteNbvReport(const NbvMission& mission,
                                                        const std::string& preset,
                                                        const std::string& dir) {
  std::vector<std::string> written;
  auto summary_path = mapstore::io::OutputPath(dir, "nbv_summary", ".txt");
  if (!summary_path.ok()) return summary_path.status();
  const common::Status wrote =
      mapstore::io::WriteFileAtomically(*summary_path, NbvSummaryTable(mission, preset));
  if (!wrote.ok()) return wrote;
  written.push_back(*summary_path);
  auto path_csv = mapstore::io::OutputPath(dir, "nbv_path", ".csv");
  if (!path_csv.ok()) return path_csv.status();
  const common::Status wrote_path =
      mapstore::io::WriteFileAtomically(*path_csv, NbvPathCsv(mission));
  if (!wrote_path.ok()) return wrote_path;
  written.push_back(*path_csv);

  const common::GridMap map = mission.info_map().ToGridMap();
  mapstore::io::PngOverlay overlay;
  overlay.path_m = mission.path_m();
  for (size_t i = 0; i < mission.view_points().size(); ++i) {
    overlay.markers.push_back({mission.view_points()[i].position_m, std::to_string(i + 1)});
  }
  char caption[160];
  const auto& views = mission.view_points();
  std::snprintf(caption, sizeof(caption), "%s: %d scans, %.1f m, coverage %.1f %%", preset.c_str(),
                mission.scans(), mission.distance_m(),
                views.empty() ? 0.0 : 100.0 * views.back().coverage);
  overlay.caption = caption;
  for (const auto& [stem, layer] :
       {std::pair<std::string, std::string>{"nbv_navigability", info_layers::kNavigability},
        {"nbv_quality", info_layers::kQuality}}) {
    auto png = mapstore::io::WritePng(dir, stem, map, layer, overlay);
    if (!png.ok()) return png.status();
    written.push_back(*png);
  }
  return written;
}

}  // namespace cairn::explore
