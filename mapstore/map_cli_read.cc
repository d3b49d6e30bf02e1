// cairn-map's commands that only read the database: list, show, diff, profiles, audit, places.

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "common/robot_profile.h"
#include "mapstore/map_cli_support.h"
#include "mapstore/map_operations.h"
#include "mapstore/mapping_deriver.h"

namespace cairn::mapstore::cli {

namespace {

// The version's provenance, grid and storage.
void PrintSummary(const SqliteMapStore& store, const MapInfo& info) {
  const MapRef exact{info.site, info.name, info.version};
  const auto& g = info.geometry;
  Table summary({"field", "value"});
  summary.Add({"map", info.site + "/" + info.name + " version " + std::to_string(info.version)});
  summary.Add({"created", Time(info.provenance.created_utime)});
  summary.Add({"source robot", info.provenance.source_robot});
  summary.Add({"source profile",
               info.provenance.source_profile + " " + info.provenance.source_profile_hash});
  summary.Add({"code version", info.provenance.code_version});
  summary.Add({"grid", std::to_string(g.size_x) + " x " + std::to_string(g.size_y) + " cells of " +
                           Fmt("%.3g", g.resolution_m) + " m (" + Fmt("%.1f", g.length_x_m()) +
                           " x " + Fmt("%.1f", g.length_y_m()) + " m)"});
  summary.Add({"origin", Fmt("x %.3f", g.origin.x_m) + Fmt(" y %.3f", g.origin.y_m) +
                             Fmt(" yaw %.4f rad", g.origin.yaw_rad)});
  summary.Add({"tiles", std::to_string(info.tile_size) + " cells per side"});
  auto bytes = store.BaseBytes(exact);
  if (bytes.ok()) summary.Add({"stored base bytes", std::to_string(*bytes)});
  summary.Add({"octomap", info.has_octomap ? "yes" : "no"});
  summary.Print();
  if (!info.provenance.parameters.empty()) {
    std::printf("\nparameters:\n%s\n", info.provenance.parameters.c_str());
  }
}

// How much of each layer is known, and its range.
void PrintLayers(const common::GridMap& map) {
  Table layers({"layer", "known", "min", "max", "mean"});
  for (const std::string& name : map.layer_names()) {
    const common::Layer& l = map.at(name);
    int64_t known = 0;
    double lo = INFINITY, hi = -INFINITY, sum = 0;
    for (Eigen::Index i = 0; i < l.size(); ++i) {
      const float v = l.data()[i];
      if (std::isnan(v)) continue;
      ++known;
      lo = std::min<double>(lo, v);
      hi = std::max<double>(hi, v);
      sum += v;
    }
    layers.Add({name, Fmt("%.1f%%", 100.0 * known / std::max<int64_t>(1, l.size())),
                known ? Fmt("%.4g", lo) : "-", known ? Fmt("%.4g", hi) : "-",
                known ? Fmt("%.4g", sum / known) : "-"});
  }
  layers.Print();
}

void PrintObstacles(const common::ObstacleRegistry& obstacles) {
  std::printf("\n%zu obstacles\n", obstacles.obstacles.size());
  if (obstacles.obstacles.empty()) return;
  Table t({"id", "kind", "x_m", "y_m", "slope_deg", "height_m", "width_m", "verdicts"});
  for (const auto& o : obstacles.obstacles) {
    std::vector<std::string> verdicts;
    for (const auto& v : o.verdicts) {
      verdicts.push_back(v.profile + ":" + common::VerdictWord(v));
    }
    t.Add({std::to_string(o.id), common::ObstacleKindName(o.kind), Fmt("%.2f", o.centroid_m.x()),
           Fmt("%.2f", o.centroid_m.y()), Fmt("%.1f", o.slope_rad * 180.0 / M_PI),
           Fmt("%.3f", o.height_m), Fmt("%.2f", o.width_m), Join(verdicts, " ")});
    // A terrace's parts, numbered id.k, each with its verdicts both ways.
    for (size_t k = 0; k < o.parts.size(); ++k) {
      const common::ObstaclePart& p = o.parts[k];
      std::vector<std::string> part_verdicts;
      for (const auto& v : p.verdicts) {
        part_verdicts.push_back(v.profile + ":" + common::VerdictWord(v));
      }
      t.Add({std::to_string(o.id) + "." + std::to_string(k + 1),
             std::string("  ") + common::ObstacleKindName(p.kind), Fmt("%.2f", p.centroid_m.x()),
             Fmt("%.2f", p.centroid_m.y()), Fmt("%.1f", p.slope_rad * 180.0 / M_PI),
             Fmt("%.3f", p.height_m), Fmt("%.2f", p.width_m), Join(part_verdicts, " ")});
    }
  }
  t.Print();
}

// The cached derivations of the version and the map's history.
void PrintCacheAndHistory(const SqliteMapStore& store, const MapInfo& info) {
  auto derived = store.ListDerived({info.site, info.name, info.version});
  if (derived.ok()) {
    std::printf("\n%zu cached derivations\n", derived->size());
    if (!derived->empty()) {
      Table t({"profile", "hash", "code", "created", "layers"});
      for (const auto& d : *derived) {
        t.Add({d.profile_name, d.profile_hash, d.code_version, Time(d.created_utime),
               Join(d.layers)});
      }
      t.Print();
    }
  }
  auto audit = store.ListAudit(1000);
  if (audit.ok()) {
    std::printf("\nhistory\n");
    Table t({"time", "actor", "op", "version", "detail"});
    for (const auto& e : *audit) {
      if (e.site == info.site && e.map == info.name) {
        t.Add({Time(e.utime), e.actor, e.op, std::to_string(e.version), e.detail});
      }
    }
    t.Print();
  }
}

}  // namespace

int CmdShow(int argc, char** argv) {
  Common c;
  common::FlagParser flags("cairn-map show", "Summary of one map version.");
  c.AddDb(&flags);
  c.AddMap(&flags);
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  if (int rc = NeedMap(c); rc >= 0) return rc;
  auto store = OpenStore(c.db, false);
  if (!store.ok()) return Fail(store.status());
  auto info = (*store)->GetMapInfo(c.ref());
  if (!info.ok()) return Fail(info.status());
  const MapRef exact{info->site, info->name, info->version};
  PrintSummary(**store, *info);
  std::printf("\n");
  auto map = (*store)->LoadLayers(exact, {});
  if (!map.ok()) return Fail(map.status());
  PrintLayers(*map);
  auto obstacles = (*store)->LoadObstacles(exact);
  if (!obstacles.ok()) return Fail(obstacles.status());
  PrintObstacles(*obstacles);
  PrintCacheAndHistory(**store, *info);
  return 0;
}

int CmdList(int argc, char** argv) {
  Common c;
  bool all_versions = false, deleted = false;
  std::string site;
  common::FlagParser flags("cairn-map list", "Lists the stored maps (the latest version of each).");
  c.AddDb(&flags);
  flags.AddString("site", &site, "only this site");
  flags.AddBool("all-versions", &all_versions, "every version, not only the latest");
  flags.AddBool("deleted", &deleted, "include deleted versions");
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  auto store = OpenStore(c.db, false);
  if (!store.ok()) return Fail(store.status());
  auto maps = (*store)->ListMaps({site, "", all_versions, deleted});
  if (!maps.ok()) return Fail(maps.status());
  Table t({"site", "map", "version", "created", "robot", "profile", "cells", "res_m", "layers",
           "obstacles", "octomap", "state"});
  for (const MapInfo& m : *maps) {
    t.Add({m.site, m.name, std::to_string(m.version), Time(m.provenance.created_utime),
           m.provenance.source_robot, m.provenance.source_profile,
           std::to_string(m.geometry.size_x) + "x" + std::to_string(m.geometry.size_y),
           Fmt("%.3g", m.geometry.resolution_m), std::to_string(m.layers.size()),
           std::to_string(m.num_obstacles), m.has_octomap ? "yes" : "no",
           m.deleted ? "deleted" : "ok"});
  }
  t.Print();
  std::printf("%zu map%s\n", maps->size(), maps->size() == 1 ? "" : "s");
  return 0;
}

int CmdDiff(int argc, char** argv) {
  Common c;
  int version_b = 0;
  std::string map_b, profile_a, profile_b;
  double tolerance = 0.0;
  common::FlagParser flags(
      "cairn-map diff",
      "Compares two map versions (--version, --version-b, --map-b), or one version "
      "under two profiles (--profile-a, --profile-b): cells and obstacles that "
      "differ. Exit status 0 when identical, 1 when they differ.");
  c.AddDb(&flags);
  c.AddMap(&flags);
  flags.AddString("map-b", &map_b, "second map (default: the same map)");
  flags.AddInt("version-b", &version_b, "version of the second map (0 = latest)");
  flags.AddString("profile-a", &profile_a, "compare this profile's view ...");
  flags.AddString("profile-b", &profile_b, "... with this one's");
  flags.AddDouble("tolerance", &tolerance, "largest difference still counted as equal");
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  if (int rc = NeedMap(c); rc >= 0) return rc;
  auto store = OpenStore(c.db, false);
  if (!store.ok()) return Fail(store.status());
  const ProfileDeriver deriver = MappingDeriver();
  common::Result<MapDiff> diff = common::InternalError("no diff");
  if (!profile_a.empty() || !profile_b.empty()) {
    if (profile_a.empty() || profile_b.empty()) {
      std::fprintf(stderr, "cairn-map: give both --profile-a and --profile-b\n");
      return 2;
    }
    diff = DiffProfiles(**store, &deriver, c.ref(), profile_a, profile_b);
  } else {
    diff = DiffVersions(**store, c.ref(), {c.site, map_b.empty() ? c.map : map_b, version_b}, {},
                        tolerance);
  }
  if (!diff.ok()) return Fail(diff.status());
  std::printf("A: %s\nB: %s\n", diff->a_label.c_str(), diff->b_label.c_str());
  Table t({"layer A", "layer B", "cells compared", "cells different", "first differences"});
  for (const auto& l : diff->layers) {
    std::vector<std::string> examples;
    for (const auto& e : l.examples) {
      examples.push_back("(" + std::to_string(e.ix) + "," + std::to_string(e.iy) + ")");
    }
    t.Add({l.layer_a.empty() ? "(absent)" : l.layer_a, l.layer_b.empty() ? "(absent)" : l.layer_b,
           std::to_string(l.cells_compared), std::to_string(l.cells_different),
           Join(examples, " ")});
  }
  t.Print();
  std::printf("\n%zu obstacles differ\n", diff->obstacles.size());
  for (const auto& o : diff->obstacles) std::printf("  %d: %s\n", o.id, o.what.c_str());
  return diff->identical() ? 0 : 1;
}

int CmdProfiles(int argc, char** argv) {
  Common c;
  common::FlagParser flags("cairn-map profiles", "Lists the stored robot profiles.");
  c.AddDb(&flags);
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  auto store = OpenStore(c.db, false);
  if (!store.ok()) return Fail(store.status());
  auto profiles = (*store)->ListProfiles();
  if (!profiles.ok()) return Fail(profiles.status());
  Table t({"profile", "hash", "drive", "slope_up_deg", "step_up_m", "step_down_m", "updated"});
  for (const auto& p : *profiles) {
    t.Add({p.profile.name, p.content_hash, common::DriveKindName(p.profile.drive),
           Fmt("%.1f", p.profile.max_slope_up_rad * 180.0 / M_PI),
           Fmt("%.3f", p.profile.max_step_up_m), Fmt("%.3f", p.profile.max_step_down_m),
           Time(p.updated_utime)});
  }
  t.Print();
  return 0;
}

int CmdAudit(int argc, char** argv) {
  Common c;
  int limit = 50;
  common::FlagParser flags("cairn-map audit", "The newest changes to the database.");
  c.AddDb(&flags);
  flags.AddInt("limit", &limit, "how many entries");
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  auto store = OpenStore(c.db, false);
  if (!store.ok()) return Fail(store.status());
  auto audit = (*store)->ListAudit(limit);
  if (!audit.ok()) return Fail(audit.status());
  Table t({"time", "actor", "op", "site", "map", "version", "request", "detail"});
  for (const auto& e : *audit) {
    t.Add({Time(e.utime), e.actor, e.op, e.site, e.map, std::to_string(e.version),
           std::to_string(e.request_id), e.detail});
  }
  t.Print();
  return 0;
}

int CmdPlaces(int argc, char** argv) {
  Common c;
  common::FlagParser flags("cairn-map places", "The semantic places (rooms) of a site.");
  c.AddDb(&flags);
  flags.AddString("site", &c.site, "site");
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  auto store = OpenStore(c.db, false);
  if (!store.ok()) return Fail(store.status());
  auto places = (*store)->ListPlaces(c.site);
  if (!places.ok()) return Fail(places.status());
  Table t({"place", "vertices", "polygon_m"});
  for (const auto& p : *places) {
    std::vector<std::string> v;
    for (const auto& x : p.polygon_m) v.push_back(Fmt("(%.2f", x.x()) + Fmt(" %.2f)", x.y()));
    t.Add({p.name, std::to_string(p.polygon_m.size()), Join(v, " ")});
  }
  t.Print();
  return 0;
}

}  // namespace cairn::mapstore::cli
