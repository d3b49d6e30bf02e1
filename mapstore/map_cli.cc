#include "mapstore/map_cli.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "common/flags.h"
#include "common/layers.h"
#include "common/robot_profile.h"
#include "mapstore/map_operations.h"
#include "mapstore/map_transfer.h"
#include "mapstore/sqlite_map_store.h"
#include "mapstore/mapping_deriver.h"

namespace cairn::mapstore {
namespace {

namespace fs = std::filesystem;
using common::FlagParser;
using common::Status;

constexpr char kDefaultDb[] = "var/cairn.db";
constexpr char kActor[] = "cairn-map";

// ---- Output helpers ----

// Aligned columns, header first.
class Table {
 public:
  explicit Table(std::vector<std::string> header) { rows_.push_back(std::move(header)); }
  void Add(std::vector<std::string> row) { rows_.push_back(std::move(row)); }
  void Print() const {
    std::vector<size_t> width;
    for (const auto& row : rows_) {
      width.resize(std::max(width.size(), row.size()));
      for (size_t i = 0; i < row.size(); ++i) width[i] = std::max(width[i], row[i].size());
    }
    for (size_t r = 0; r < rows_.size(); ++r) {
      std::string line;
      for (size_t i = 0; i < rows_[r].size(); ++i) {
        std::string cell = rows_[r][i];
        if (i + 1 < rows_[r].size()) cell.resize(width[i], ' ');
        line += (i == 0 ? "" : "  ") + cell;
      }
      std::printf("%s\n", line.c_str());
      if (r == 0) {
        size_t total = 0;
        for (size_t w : width) total += w + 2;
        std::printf("%s\n", std::string(total > 2 ? total - 2 : 0, '-').c_str());
      }
    }
  }

 private:
  std::vector<std::vector<std::string>> rows_;
};

std::string Fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, v);
  return buf;
}

std::string Time(int64_t utime) {
  if (utime <= 0) return "-";
  const std::time_t t = static_cast<std::time_t>(utime / 1000000);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%d %H:%M:%SZ", &tm);
  return buf;
}

std::string Join(const std::vector<std::string>& items, const char* sep = ", ") {
  std::string out;
  for (const auto& i : items) out += (out.empty() ? "" : sep) + i;
  return out;
}

int Fail(const Status& s) {
  std::fprintf(stderr, "cairn-map: %s\n", s.ToString().c_str());
  return 1;
}

// A progress bar on a terminal, nothing otherwise.
ProgressFn TerminalProgress() {
  if (!isatty(STDOUT_FILENO)) return nullptr;
  return [](double fraction, const std::string& stage) {
    const int filled = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * 30);
    std::printf("\r[%s%s] %3d%% %-24s", std::string(filled, '#').c_str(),
                std::string(30 - filled, ' ').c_str(), static_cast<int>(fraction * 100),
                stage.c_str());
    if (fraction >= 1.0) std::printf("\n");
    std::fflush(stdout);
  };
}

ProfileDeriver Deriver() {
  return MappingDeriver();
}

// Common flags of every command.
struct Common {
  std::string db{kDefaultDb};
  std::string site{kDefaultSite};
  std::string map;
  int version{0};
  void AddDb(FlagParser* f) { f->AddString("db", &db, "database file"); }
  void AddMap(FlagParser* f, bool with_version = true) {
    f->AddString("site", &site, "site");
    f->AddString("map", &map, "map name");
    if (with_version) f->AddInt("version", &version, "map version (0 = latest)");
  }
  MapRef ref() const { return {site, map, version}; }
};

common::Result<std::unique_ptr<SqliteMapStore>> OpenStore(const std::string& path, bool write) {
  SqliteOptions options;
  options.read_only = !write;
  options.create_if_missing = write;
  return SqliteMapStore::Open(path, options);
}

// Parses a command's flags; returns -1 to go on, else the exit code.
int ParseFlags(FlagParser* flags, int argc, char** argv) { return flags->Parse(argc, argv); }

int NeedMap(const Common& c) {
  if (c.map.empty()) {
    std::fprintf(stderr, "cairn-map: --map is required (see --help)\n");
    return 2;
  }
  return -1;
}

// ---- Commands ----

int CmdList(int argc, char** argv) {
  Common c;
  bool all_versions = false, deleted = false;
  std::string site;
  FlagParser flags("cairn-map list", "Lists the stored maps (the latest version of each).");
  c.AddDb(&flags);
  flags.AddString("site", &site, "only this site");
  flags.AddBool("all-versions", &all_versions, "every version, not only the latest");
  flags.AddBool("deleted", &deleted, "include deleted versions");
  if (int rc = ParseFlags(&flags, argc, argv); rc >= 0) return rc;
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

int CmdShow(int argc, char** argv) {
  Common c;
  FlagParser flags("cairn-map show", "Summary of one map version.");
  c.AddDb(&flags);
  c.AddMap(&flags);
  if (int rc = ParseFlags(&flags, argc, argv); rc >= 0) return rc;
  if (int rc = NeedMap(c); rc >= 0) return rc;
  auto store = OpenStore(c.db, false);
  if (!store.ok()) return Fail(store.status());
  auto info = (*store)->GetMapInfo(c.ref());
  if (!info.ok()) return Fail(info.status());
  const MapRef exact{info->site, info->name, info->version};
  const auto& g = info->geometry;
  Table summary({"field", "value"});
  summary.Add({"map", info->site + "/" + info->name + " version " + std::to_string(info->version)});
  summary.Add({"created", Time(info->provenance.created_utime)});
  summary.Add({"source robot", info->provenance.source_robot});
  summary.Add({"source profile",
               info->provenance.source_profile + " " + info->provenance.source_profile_hash});
  summary.Add({"code version", info->provenance.code_version});
  summary.Add({"grid", std::to_string(g.size_x) + " x " + std::to_string(g.size_y) + " cells of " +
                           Fmt("%.3g", g.resolution_m) + " m (" + Fmt("%.1f", g.length_x_m()) +
                           " x " + Fmt("%.1f", g.length_y_m()) + " m)"});
  summary.Add({"origin", Fmt("x %.3f", g.origin.x_m) + Fmt(" y %.3f", g.origin.y_m) +
                             Fmt(" yaw %.4f rad", g.origin.yaw_rad)});
  summary.Add({"tiles", std::to_string(info->tile_size) + " cells per side"});
  auto bytes = (*store)->BaseBytes(exact);
  if (bytes.ok()) summary.Add({"stored base bytes", std::to_string(*bytes)});
  summary.Add({"octomap", info->has_octomap ? "yes" : "no"});
  summary.Print();
  if (!info->provenance.parameters.empty()) {
    std::printf("\nparameters:\n%s\n", info->provenance.parameters.c_str());
  }

  std::printf("\n");
  auto map = (*store)->LoadLayers(exact, {});
  if (!map.ok()) return Fail(map.status());
  Table layers({"layer", "known", "min", "max", "mean"});
  for (const std::string& name : map->layer_names()) {
    const common::Layer& l = map->at(name);
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

  auto obstacles = (*store)->LoadObstacles(exact);
  if (!obstacles.ok()) return Fail(obstacles.status());
  std::printf("\n%zu obstacles\n", obstacles->obstacles.size());
  if (!obstacles->obstacles.empty()) {
    Table t({"id", "kind", "x_m", "y_m", "slope_deg", "height_m", "width_m", "verdicts"});
    for (const auto& o : obstacles->obstacles) {
      std::vector<std::string> verdicts;
      for (const auto& v : o.verdicts) {
        verdicts.push_back(v.profile + ":" + (v.crossable ? "crossable" : "blocked"));
      }
      t.Add({std::to_string(o.id), common::ObstacleKindName(o.kind), Fmt("%.2f", o.centroid_m.x()),
             Fmt("%.2f", o.centroid_m.y()), Fmt("%.1f", o.slope_rad * 180.0 / M_PI),
             Fmt("%.3f", o.height_m), Fmt("%.2f", o.width_m), Join(verdicts, " ")});
    }
    t.Print();
  }
  auto derived = (*store)->ListDerived(exact);
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
  auto audit = (*store)->ListAudit(1000);
  if (audit.ok()) {
    std::printf("\nhistory\n");
    Table t({"time", "actor", "op", "version", "detail"});
    for (const auto& e : *audit) {
      if (e.site == info->site && e.map == info->name) {
        t.Add({Time(e.utime), e.actor, e.op, std::to_string(e.version), e.detail});
      }
    }
    t.Print();
  }
  return 0;
}

int CmdExport(int argc, char** argv) {
  Common c;
  std::string format = "ros", out, mode = "trinary", layer, profile, stem;
  double occupied = 0.65, free_thresh = 0.196;
  FlagParser flags("cairn-map export",
                   "Writes a stored map to files: ROS map_server YAML + PGM (--mode trinary, "
                   "scale or raw), PNG with a legend, OctoMap .bt/.ot, or a CSV of obstacles. "
                   "Files go into --out and nowhere else.");
  c.AddDb(&flags);
  c.AddMap(&flags);
  flags.AddString("format", &format, "ros, png, bt, ot or csv");
  flags.AddString("out", &out, "target folder (created if missing)");
  flags.AddString("mode", &mode, "ros: trinary, scale or raw (raw keeps 0..100 exactly)");
  flags.AddString("layer", &layer, "ros/png: layer to write (default: see cairn-map help)");
  flags.AddString("profile", &profile, "derive this profile's layers (cost/<profile>, verdicts)");
  flags.AddString("stem", &stem, "file name stem (default <map>_v<version>[_<layer>])");
  flags.AddDouble("occupied-thresh", &occupied, "ros: occupied above this probability");
  flags.AddDouble("free-thresh", &free_thresh, "ros: free below this probability");
  if (int rc = ParseFlags(&flags, argc, argv); rc >= 0) return rc;
  if (int rc = NeedMap(c); rc >= 0) return rc;
  if (out.empty()) {
    std::fprintf(stderr, "cairn-map: --out is required\n");
    return 2;
  }
  auto parsed_mode = io::PgmModeFromName(mode);
  if (!parsed_mode.ok()) return Fail(parsed_mode.status());
  auto store = OpenStore(c.db, false);
  if (!store.ok()) return Fail(store.status());
  const ProfileDeriver deriver = Deriver();
  ExportOptions options;
  options.ref = c.ref();
  options.format = format;
  options.folder = out;
  options.layer = layer;
  options.profile = profile;
  options.stem = stem;
  options.ros.mode = *parsed_mode;
  options.ros.occupied_thresh = occupied;
  options.ros.free_thresh = free_thresh;
  const ProgressFn progress = TerminalProgress();
  if (progress) progress(0.1, "exporting");
  auto files = ExportMap(**store, &deriver, options);
  if (progress) progress(1.0, "done");
  if (!files.ok()) return Fail(files.status());
  for (const std::string& f : *files) std::printf("%s\n", f.c_str());
  return 0;
}

int CmdImport(int argc, char** argv) {
  Common c;
  std::string file, layer = layers::kStaticMap, robot, profile;
  FlagParser flags("cairn-map import",
                   "Imports a file as a new version of a map: a ROS map_server YAML + PGM "
                   "(hand-drawn static maps too) into --layer, an OctoMap .bt/.ot, or an obstacle "
                   "CSV. The new version keeps the latest version's other content.");
  c.AddDb(&flags);
  c.AddMap(&flags, false);
  flags.AddString("file", &file, "the .yaml, .bt, .ot or .csv file");
  flags.AddString("layer", &layer, "layer that receives a YAML map");
  flags.AddString("robot", &robot, "source robot recorded in the provenance");
  flags.AddString("profile", &profile, "source profile recorded in the provenance");
  if (int rc = ParseFlags(&flags, argc, argv); rc >= 0) return rc;
  if (int rc = NeedMap(c); rc >= 0) return rc;
  if (file.empty()) {
    std::fprintf(stderr, "cairn-map: --file is required\n");
    return 2;
  }
  auto store = OpenStore(c.db, true);
  if (!store.ok()) return Fail(store.status());
  ImportOptions options;
  options.path = file;
  options.site = c.site;
  options.name = c.map;
  options.layer = layer;
  options.provenance.source_robot = robot;
  options.provenance.source_profile = profile;
  auto info = ImportMap(**store, options, {kActor, 0, 0});
  if (!info.ok()) return Fail(info.status());
  std::printf("imported %s as %s/%s version %lld (layers: %s)\n", file.c_str(), info->site.c_str(),
              info->name.c_str(), static_cast<long long>(info->version),
              Join(info->layers).c_str());
  return 0;
}

int CmdShare(int argc, char** argv) {
  Common c;
  std::string profile;
  FlagParser flags("cairn-map share",
                   "Derives a map's layers for another robot profile (cached in the database) "
                   "and lists the obstacles whose verdict differs from the source profile's.");
  c.AddDb(&flags);
  c.AddMap(&flags);
  flags.AddString("profile", &profile, "target profile (stored with put-profile)");
  if (int rc = ParseFlags(&flags, argc, argv); rc >= 0) return rc;
  if (int rc = NeedMap(c); rc >= 0) return rc;
  if (profile.empty()) {
    std::fprintf(stderr, "cairn-map: --profile is required\n");
    return 2;
  }
  const ProfileDeriver deriver = Deriver();
  if (!deriver.valid()) return Fail(common::UnavailableError("built without the mapping core"));
  auto store = OpenStore(c.db, true);
  if (!store.ok()) return Fail(store.status());
  const ProgressFn progress = TerminalProgress();
  if (progress) progress(0.1, "deriving " + profile);
  auto shared = ShareMap(**store, deriver, c.ref(), profile, {kActor, 0, 0});
  if (progress) progress(1.0, "done");
  if (!shared.ok()) return Fail(shared.status());
  std::printf("%s/%s version %lld for %s: layers %s (%s)\n", shared->info.site.c_str(),
              shared->info.name.c_str(), static_cast<long long>(shared->info.version),
              profile.c_str(), Join(shared->derived.layers.layer_names()).c_str(),
              shared->was_cached ? "from the cache" : "derived and cached");
  std::printf("%zu obstacles change verdict from %s to %s\n", shared->changed.size(),
              shared->source_profile.empty() ? "(unknown)" : shared->source_profile.c_str(),
              profile.c_str());
  if (!shared->changed.empty()) {
    Table t({"id", "kind", "x_m", "y_m", "before", "after"});
    for (const auto& o : shared->changed) {
      auto text = [](const common::ObstacleVerdict& v) {
        return v.profile + ": " + (v.crossable ? "crossable" : "blocked (" + v.reason + ")");
      };
      t.Add({std::to_string(o.id), common::ObstacleKindName(o.kind), Fmt("%.2f", o.centroid_m.x()),
             Fmt("%.2f", o.centroid_m.y()), o.verdicts.size() > 1 ? text(o.verdicts[0]) : "-",
             text(o.verdicts.back())});
    }
    t.Print();
  }
  return 0;
}

int CmdDiff(int argc, char** argv) {
  Common c;
  int version_b = 0;
  std::string map_b, profile_a, profile_b;
  double tolerance = 0.0;
  FlagParser flags("cairn-map diff",
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
  if (int rc = ParseFlags(&flags, argc, argv); rc >= 0) return rc;
  if (int rc = NeedMap(c); rc >= 0) return rc;
  auto store = OpenStore(c.db, false);
  if (!store.ok()) return Fail(store.status());
  const ProfileDeriver deriver = Deriver();
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

int CmdCheck(int argc, char** argv) {
  Common c;
  FlagParser flags("cairn-map check",
                   "Checks a database: that it is a cairn database of a known schema, "
                   "PRAGMA integrity_check, foreign keys, and every stored blob against its "
                   "checksum. Exit status 0 when sound, 1 otherwise.");
  c.AddDb(&flags);
  if (int rc = ParseFlags(&flags, argc, argv); rc >= 0) return rc;
  auto store = OpenStore(c.db, false);
  if (!store.ok()) return Fail(store.status());
  auto report = (*store)->Check(TerminalProgress());
  if (!report.ok()) return Fail(report.status());
  for (const std::string& p : report->problems) std::printf("problem: %s\n", p.c_str());
  std::printf("%s: %lld map versions, %lld blobs checked: %s\n", c.db.c_str(),
              static_cast<long long>(report->maps_checked),
              static_cast<long long>(report->blobs_checked), report->ok ? "ok" : "DAMAGED");
  return report->ok ? 0 : 1;
}

int CmdVacuum(int argc, char** argv) {
  Common c;
  FlagParser flags("cairn-map vacuum",
                   "Removes blobs that no version or cache refers to and compacts the file. "
                   "Soft-deleted maps keep their data.");
  c.AddDb(&flags);
  if (int rc = ParseFlags(&flags, argc, argv); rc >= 0) return rc;
  auto store = OpenStore(c.db, true);
  if (!store.ok()) return Fail(store.status());
  auto shrunk = (*store)->Vacuum(TerminalProgress());
  if (!shrunk.ok()) return Fail(shrunk.status());
  std::printf("%s: %lld bytes freed\n", c.db.c_str(), static_cast<long long>(*shrunk));
  return 0;
}

int CmdMigrate(int argc, char** argv) {
  Common c;
  FlagParser flags("cairn-map migrate",
                   "Opens a database for writing, which migrates an older schema to the current "
                   "one in a single transaction.");
  c.AddDb(&flags);
  if (int rc = ParseFlags(&flags, argc, argv); rc >= 0) return rc;
  SqliteOptions options;
  options.create_if_missing = false;
  auto store = SqliteMapStore::Open(c.db, options);
  if (!store.ok()) return Fail(store.status());
  std::printf("%s: schema version %d\n", c.db.c_str(), (*store)->schema_version());
  return 0;
}

int CmdProfiles(int argc, char** argv) {
  Common c;
  FlagParser flags("cairn-map profiles", "Lists the stored robot profiles.");
  c.AddDb(&flags);
  if (int rc = ParseFlags(&flags, argc, argv); rc >= 0) return rc;
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

int CmdPutProfile(int argc, char** argv) {
  Common c;
  std::string file;
  FlagParser flags("cairn-map put-profile",
                   "Stores a robot profile YAML (config/profiles/*.yaml); storing the same "
                   "content again changes nothing.");
  c.AddDb(&flags);
  flags.AddString("file", &file, "profile YAML");
  if (int rc = ParseFlags(&flags, argc, argv); rc >= 0) return rc;
  if (file.empty()) {
    std::fprintf(stderr, "cairn-map: --file is required\n");
    return 2;
  }
  common::RobotProfile profile;
  try {
    profile = common::LoadRobotProfileFile(file);
  } catch (const std::exception& e) {
    return Fail(common::InvalidArgumentError(e.what()));
  }
  auto store = OpenStore(c.db, true);
  if (!store.ok()) return Fail(store.status());
  Status s = (*store)->PutProfile(profile, {kActor, 0, 0});
  if (!s.ok()) return Fail(s);
  std::printf("profile %s stored (%s)\n", profile.name.c_str(), profile.ContentHash().c_str());
  return 0;
}

int CmdDelete(int argc, char** argv) {
  Common c;
  FlagParser flags("cairn-map delete",
                   "Marks a map (every version, or --version) deleted. The data stay; lists and "
                   "loads no longer show it.");
  c.AddDb(&flags);
  c.AddMap(&flags);
  if (int rc = ParseFlags(&flags, argc, argv); rc >= 0) return rc;
  if (int rc = NeedMap(c); rc >= 0) return rc;
  auto store = OpenStore(c.db, true);
  if (!store.ok()) return Fail(store.status());
  Status s = (*store)->DeleteMap(c.ref(), {kActor, 0, 0});
  if (!s.ok()) return Fail(s);
  std::printf("deleted %s/%s%s\n", c.site.c_str(), c.map.c_str(),
              c.version == 0 ? "" : (" version " + std::to_string(c.version)).c_str());
  return 0;
}

int CmdAudit(int argc, char** argv) {
  Common c;
  int limit = 50;
  FlagParser flags("cairn-map audit", "The newest changes to the database.");
  c.AddDb(&flags);
  flags.AddInt("limit", &limit, "how many entries");
  if (int rc = ParseFlags(&flags, argc, argv); rc >= 0) return rc;
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
  FlagParser flags("cairn-map places", "The semantic places (rooms) of a site.");
  c.AddDb(&flags);
  flags.AddString("site", &c.site, "site");
  if (int rc = ParseFlags(&flags, argc, argv); rc >= 0) return rc;
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

// `cairn-map serve` is cairn-map-server (it needs the bus, this program does not): run the
// sibling executable in place of this process, with the same flags (and the same pid, so a
// launcher watching it sees one process).
int CmdServe(int argc, char** argv) {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  const std::string server =
      ec ? std::string("cairn-map-server") : (self.parent_path() / "cairn-map-server").string();
  std::vector<std::string> args = {server};
  for (int i = 1; i < argc; ++i) args.emplace_back(argv[i]);
  std::vector<char*> exec_argv;
  for (auto& a : args) exec_argv.push_back(a.data());
  exec_argv.push_back(nullptr);
  execvp(server.c_str(), exec_argv.data());
  std::fprintf(stderr, "cairn-map serve: cannot run %s: %s\n", server.c_str(),
               std::strerror(errno));
  return 1;
}

struct Command {
  const char* name;
  const char* summary;
  std::function<int(int, char**)> run;
};

const std::vector<Command>& Commands() {
  static const std::vector<Command> commands = {
      {"list", "list stored maps", CmdList},
      {"show", "summary of one map version", CmdShow},
      {"export", "write a map as ROS YAML+PGM, PNG, OctoMap or CSV", CmdExport},
      {"import", "read a YAML+PGM, OctoMap or CSV into a new version", CmdImport},
      {"share", "derive a map for another profile; verdicts that change", CmdShare},
      {"diff", "compare two versions, or one version under two profiles", CmdDiff},
      {"check", "integrity check (exit 1 when damaged)", CmdCheck},
      {"vacuum", "drop unreferenced blobs, compact the file", CmdVacuum},
      {"migrate", "migrate an older schema", CmdMigrate},
      {"profiles", "list robot profiles", CmdProfiles},
      {"put-profile", "store a robot profile YAML", CmdPutProfile},
      {"delete", "soft-delete a map or version", CmdDelete},
      {"audit", "recent changes", CmdAudit},
      {"places", "semantic places of a site", CmdPlaces},
      {"serve", "serve a stored map to a robot on the bus (cairn-map-server)", CmdServe},
  };
  return commands;
}

void Usage(FILE* out) {
  std::fprintf(out,
               "usage: cairn-map <command> [flags]   (cairn-map <command> --help for its flags)\n\n"
               "Works on a cairn map database directly (default %s).\n\ncommands:\n",
               kDefaultDb);
  for (const Command& c : Commands()) std::fprintf(out, "  %-12s %s\n", c.name, c.summary);
  std::fprintf(out,
               "\nDefault export layer: cost/<profile> with --profile; else for ros the first of "
               "final, static, occupancy, occupancy_logodds, long_term, short_term; for png "
               "elevation.\nExit status: 0 success, 1 failure (or damage found), 2 bad usage.\n");
}

}  // namespace

int RunMapCli(int argc, char** argv) {
  if (argc < 2) {
    Usage(stderr);
    return 2;
  }
  const std::string command = argv[1];
  if (command == "--help" || command == "-h" || command == "help") {
    Usage(stdout);
    return 0;
  }
  for (const Command& c : Commands()) {
    if (command == c.name) {
      try {
        return c.run(argc - 1, argv + 1);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "cairn-map %s: %s\n", c.name, e.what());
        return 1;
      }
    }
  }
  std::fprintf(stderr, "cairn-map: unknown command '%s'\n\n", command.c_str());
  Usage(stderr);
  return 2;
}

}  // namespace cairn::mapstore
