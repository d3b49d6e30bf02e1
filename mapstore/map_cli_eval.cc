// cairn-map eval: a stored map against the ground truth of a simulator world.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

#include "common/layers.h"
#include "mapstore/map_cli_support.h"
#include "mapstore/map_eval.h"
#include "mapstore/map_operations.h"
#include "mapstore/mapping_deriver.h"
#include "simulator/ground_truth.h"
#include "simulator/mujoco_model.h"
#include "simulator/scenario.h"

#ifndef CAIRN_SIM_DATA_DIR
#define CAIRN_SIM_DATA_DIR "simulator"
#endif

namespace cairn::mapstore::cli {

static_assert(std::string_view(sim::kTruthOccupiedLayer) == std::string_view(kTruthOccupied));
static_assert(std::string_view(sim::kTruthGroundLayer) == std::string_view(kTruthGround));

namespace {

namespace fs = std::filesystem;

// "x,y" in metres.
bool ParseStart(const std::string& text, common::Vector2* out) {
  const size_t comma = text.find(',');
  if (comma == std::string::npos) return false;
  try {
    size_t used_x = 0, used_y = 0;
    const std::string xs = text.substr(0, comma), ys = text.substr(comma + 1);
    const double x = std::stod(xs, &used_x);
    const double y = std::stod(ys, &used_y);
    if (used_x != xs.size() || used_y != ys.size() || !std::isfinite(x) || !std::isfinite(y)) {
      return false;
    }
    *out = {x, y};
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

std::string Percent(double v) { return std::isfinite(v) ? Fmt("%.1f%%", 100.0 * v) : "-"; }
std::string Cells(int64_t n, int64_t of) {
  return std::to_string(n) + " of " + std::to_string(of) + " cells";
}

void PrintReport(const MapEvalReport& r, const MapEvalParams& p) {
  const std::string tol =
      "within " + std::to_string(p.tolerance_cells) + " cell" + (p.tolerance_cells == 1 ? "" : "s");
  Table t({"figure", "value", "detail"});
  t.Add({"occupied precision", Percent(r.occupied_precision),
         "map-occupied cells with a true obstacle " + tol + " (" +
             std::to_string(r.map_occupied_cells) + " map-occupied)"});
  t.Add({"occupied recall", Percent(r.occupied_recall),
         "true obstacle cells with a map-occupied cell " + tol + " (" +
             std::to_string(r.truth_occupied_cells) + " true)"});
  t.Add({"occupied recall, visible", Percent(r.occupied_recall_visible),
         "the same for obstacle cells touching the reachable area"});
  t.Add({"free precision", Percent(r.free_precision),
         "map-free cells that are free (" + std::to_string(r.map_free_cells) + " map-free)"});
  t.Add({"free precision, edges", Percent(r.free_precision_tolerant),
         "map-free cells with a free cell " + tol + " (an obstacle's edge shares the cell)"});
  t.Add({"coverage", Percent(r.coverage),
         "reachable cells known: " + Cells(r.reachable_known_cells, r.reachable_cells)});
  t.Add({"occupied IoU", Percent(r.occupied_iou), "map-occupied vs true obstacle cells"});
  t.Add(
      {"mean wall thickness",
       std::isfinite(r.mean_wall_thickness_m) ? Fmt("%.3f m", r.mean_wall_thickness_m) : "-",
       (std::isfinite(r.mean_wall_thickness_cells) ? Fmt("%.2f cells", r.mean_wall_thickness_cells)
                                                   : std::string("no cells")) +
           " over " + std::to_string(r.wall_cells_measured) + " wall cells"});
  t.Add({"double walls", std::to_string(r.double_wall_crossings),
         "row/column crossings of one wall mapped twice (" + Fmt("%.2f m", r.double_wall_length_m) +
             ")"});
  if (r.elevation && r.elevation->cells > 0) {
    t.Add({"elevation error", Fmt("%.3f m", r.elevation->mean_abs_m),
           "mean |map - ground| on " + std::to_string(r.elevation->cells) + " free cells; RMS " +
               Fmt("%.3f m", r.elevation->rms_m) + ", max " +
               Fmt("%.3f m", r.elevation->max_abs_m)});
  } else {
    t.Add({"elevation error", "-",
           r.elevation ? "no free cell known to both" : "the map has no elevation layer"});
  }
  if (r.elevation_interior && r.elevation_interior->cells > 0) {
    t.Add({"elevation, interior", Fmt("%.3f m", r.elevation_interior->mean_abs_m),
           "the same on " + std::to_string(r.elevation_interior->cells) +
               " free cells with no obstacle " + tol + "; RMS " +
               Fmt("%.3f m", r.elevation_interior->rms_m) + ", max " +
               Fmt("%.3f m", r.elevation_interior->max_abs_m)});
  }
  t.Print();
}

}  // namespace

int CmdEval(int argc, char** argv) {
  Common c;
  std::string profile, world, start_text, data_dir = CAIRN_SIM_DATA_DIR;
  bool json = false;
  MapEvalParams params;
  params.layer.clear();
  sim::TruthRasterParams truth_params;
  common::FlagParser flags(
      "cairn-map eval",
      "Judges a stored map against a simulator world's geometry: the world (no robot, doors "
      "open) is rasterised on the map's grid with MuJoCo rays (simulator/ground_truth.h), and "
      "the map's occupancy is compared with it (mapstore/map_eval.h): occupied precision and "
      "recall, free precision, coverage of the area reachable from --start, IoU, wall thickness, "
      "double walls, and the elevation error where the map has one.");
  c.AddDb(&flags);
  c.AddMap(&flags);
  flags.AddString("profile", &profile,
                  "derive this profile's layers (default layer cost/<profile>)");
  flags.AddString("world", &world, "a shipped world name (arena, tunnel, ...) or an MJCF file");
  flags.AddString(
      "layer", &params.layer,
      "map layer judged: occupancy-like 0..100, cost/<profile>, or explore/navigability "
      "(C_nc: free above 0.7, occupied below 0.4) (default occupancy, or "
      "cost/<profile> with --profile)");
  flags.AddString("region", &params.region_layer,
                  "count only the cells where this map layer is 1 (e.g. explore/work_area)");
  flags.AddString("start", &start_text,
                  "x,y (m): a free position; the reachable area grows from it");
  flags.AddDouble("band-low", &truth_params.band_low_m,
                  "geometry above ground + this (m) occupies a cell");
  flags.AddDouble("band-high", &truth_params.band_high_m,
                  "... up to ground + this (m); higher things pass overhead");
  flags.AddInt("samples", &truth_params.samples_per_side, "rays per cell side");
  flags.AddInt("threads", &truth_params.threads, "threads casting the truth's rays");
  flags.AddInt("tolerance", &params.tolerance_cells, "cells of tolerance for precision and recall");
  flags.AddDouble("occupied-above", &params.occupied_above,
                  "0..100 layers: occupied above this value");
  flags.AddDouble("free-below", &params.free_below, "0..100 layers: free below this value");
  flags.AddString("data-dir", &data_dir, "folder of the shipped worlds/ (the simulator folder)");
  flags.AddBool("json", &json, "print one JSON object instead of the table");
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  if (int rc = NeedMap(c); rc >= 0) return rc;
  if (int rc = Need(world, "world"); rc >= 0) return rc;
  if (int rc = Need(start_text, "start"); rc >= 0) return rc;
  common::Vector2 start;
  if (!ParseStart(start_text, &start)) {
    std::fprintf(stderr, "cairn-map: --start must be x,y in metres (got '%s')\n",
                 start_text.c_str());
    return 2;
  }
  params.start_m = start;
  if (params.layer.empty()) {
    params.layer = profile.empty() ? layers::kOccupancy : layers::CostLayer(profile);
  }
  params.Validate();
  truth_params.Validate();

  // The world file, before anything slow.
  sim::SimPaths paths;
  paths.data_dir = data_dir;
  const std::string world_path = paths.WorldPath(world);
  if (!fs::is_regular_file(world_path)) {
    return Fail(common::NotFoundError("world file '" + world_path + "' not found"));
  }

  auto store = OpenStore(c.db, false);
  if (!store.ok()) return Fail(store.status());
  const ProfileDeriver deriver = MappingDeriver();
  auto view = LoadForProfile(**store, &deriver, c.ref(), profile);
  if (!view.ok()) return Fail(view.status());
  const common::GridMap& map = view->layers;
  const std::string label =
      view->info.site + "/" + view->info.name + " version " + std::to_string(view->info.version);
  if (!map.HasLayer(params.layer)) {
    return Fail(common::NotFoundError(label + " has no layer '" + params.layer +
                                      "' (layers: " + Join(map.layer_names()) + ")"));
  }
  if (!map.IndexOf(start).has_value()) {
    return Fail(common::InvalidArgumentError("start (" + Fmt("%.3f", start.x()) + ", " +
                                             Fmt("%.3f", start.y()) + ") lies outside " + label +
                                             " (" + Fmt("%.2f", map.geometry().length_x_m()) +
                                             " x " + Fmt("%.2f", map.geometry().length_y_m()) +
                                             " m from (" + Fmt("%.2f", map.geometry().origin.x_m) +
                                             ", " + Fmt("%.2f", map.geometry().origin.y_m) + "))"));
  }

  sim::InstallMujocoLogHooks();
  const ProgressFn progress = json ? nullptr : TerminalProgress();
  if (progress) progress(0.1, "rasterising " + world);
  const common::GridMap truth =
      sim::GroundTruthWorld::FromFile(world_path, truth_params).Rasterise(map.geometry());
  if (progress) progress(0.9, "comparing");
  const MapEvalReport report = EvaluateMap(map, truth, params);
  if (progress) progress(1.0, "done");

  if (json) {
    std::printf("%s\n", MapEvalReportToJson(report).c_str());
    return 0;
  }
  const auto& g = map.geometry();
  std::printf("map    %s, layer %s: %d x %d cells of %s m\n", label.c_str(), params.layer.c_str(),
              g.size_x, g.size_y, Fmt("%.3g", g.resolution_m).c_str());
  std::printf("world  %s, obstacles between %s and %s m above the ground, %d x %d rays a cell\n",
              world_path.c_str(), Fmt("%.2f", truth_params.band_low_m).c_str(),
              Fmt("%.2f", truth_params.band_high_m).c_str(), truth_params.samples_per_side,
              truth_params.samples_per_side);
  std::printf(
      "cells  %lld known in the truth: %lld obstacle, %lld free; the map: %lld occupied, "
      "%lld free, %lld unknown\n\n",
      static_cast<long long>(report.truth_cells),
      static_cast<long long>(report.truth_occupied_cells),
      static_cast<long long>(report.truth_free_cells),
      static_cast<long long>(report.map_occupied_cells),
      static_cast<long long>(report.map_free_cells),
      static_cast<long long>(report.map_unknown_cells));
  PrintReport(report, params);
  return 0;
}

}  // namespace cairn::mapstore::cli
