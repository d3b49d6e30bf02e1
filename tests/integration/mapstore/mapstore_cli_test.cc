// cairn-map as a real process on real database files.

#include <filesystem>
#include <fstream>
#include <functional>

#include <gtest/gtest.h>

#include "mapstore/map_io.h"
#include "mapstore/sqlite_map_store.h"
#include "simulator/ground_truth.h"
#include "simulator/scenario.h"
#include "tests/integration/mapstore/mapstore_fixture.h"

namespace cairn::mapstore::testing {
namespace {

namespace fs = std::filesystem;

// A database written in-process (as any writer would), with an occupancy layer that holds free,
// occupied, graded and unknown cells in an asymmetric pattern.
std::string MakeDatabase(const std::string& dir, common::Layer* occupancy_out) {
  const std::string db = dir + "/site.db";
  auto store = SqliteMapStore::Open(db);
  EXPECT_TRUE(store.ok());
  MapSnapshot s = TerrainSnapshot("lab", "flat", 57, 33, 0.f);
  common::Layer& occ = s.base.AddLayer(layers::kStaticMap, 0.f);
  for (int iy = 0; iy < 33; ++iy) {
    for (int ix = 0; ix < 57; ++ix) {
      const int k = (ix * 5 + iy * 3) % 7;
      occ(ix, iy) = k == 0 ? 100.f : k == 1 ? common::kUnknown : k == 2 ? 55.f : 0.f;
    }
  }
  *occupancy_out = occ;
  EXPECT_TRUE((*store)->SaveMap(s, {"cli-test", 0, 0}).ok());
  EXPECT_TRUE((*store)->PutProfile(ShippedProfile("pioneer3at"), {"cli-test", 0, 0}).ok());
  EXPECT_TRUE((*store)->PutProfile(ShippedProfile("rover"), {"cli-test", 0, 0}).ok());
  return db;
}

// The trinary class of an occupancy value, as map_saver writes it.
int Trinary(float v) {
  if (std::isnan(v)) return -1;
  if (v >= 65.f) return 100;
  if (v <= 19.6f) return 0;
  return -1;
}

TEST(MapstoreCliTest, ExportToYamlPgmAndImportBackKeepsTheTrinaryCells) {
  ProcessSet procs(cairn::testing::PrivateLcmUrl());
  common::Layer occ;
  const std::string db = MakeDatabase(procs.dir(), &occ);
  const std::string out = procs.dir() + "/export";
  CliResult exported = RunCli(procs, {"export", "--db", db, "--site", "lab", "--map", "flat",
                                      "--format", "ros", "--mode", "trinary", "--out", out});
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  ASSERT_TRUE(fs::exists(out + "/flat_v1_static.yaml"));
  ASSERT_TRUE(fs::exists(out + "/flat_v1_static.pgm"));
  CliResult imported = RunCli(procs, {"import", "--db", db, "--site", "lab", "--map", "drawn",
                                      "--file", out + "/flat_v1_static.yaml"});
  ASSERT_EQ(imported.exit_code, 0) << imported.output;

  SqliteOptions read_only;
  read_only.read_only = true;
  auto store = SqliteMapStore::Open(db, read_only);
  ASSERT_TRUE(store.ok());
  auto back = (*store)->LoadLayers({"lab", "drawn", 0}, {{"static"}, std::nullopt});
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  auto original = (*store)->GetMapInfo({"lab", "flat", 0});
  EXPECT_EQ(back->geometry(), original->geometry);
  int free = 0, occupied = 0, unknown = 0;
  for (int iy = 0; iy < 33; ++iy) {
    for (int ix = 0; ix < 57; ++ix) {
      const int expected = Trinary(occ(ix, iy));
      const float got = back->at("static")(ix, iy);
      ASSERT_EQ(std::isnan(got) ? -1 : static_cast<int>(got), expected) << ix << "," << iy;
      free += expected == 0;
      occupied += expected == 100;
      unknown += expected == -1;
    }
  }
  EXPECT_GT(free, 0);
  EXPECT_GT(occupied, 0);
  EXPECT_GT(unknown, 0);

  // Raw mode keeps every value; PNG, CSV render; diff sees the graded cells trinary lost.
  CliResult raw = RunCli(procs, {"export", "--db", db, "--site", "lab", "--map", "flat", "--mode",
                                 "raw", "--out", out, "--stem", "raw"});
  ASSERT_EQ(raw.exit_code, 0) << raw.output;
  auto raw_map = io::ReadRosMap(out + "/raw.yaml");
  ASSERT_TRUE(raw_map.ok());
  EXPECT_TRUE(SameLayer(raw_map->occupancy, occ));
  CliResult png = RunCli(procs, {"export", "--db", db, "--site", "lab", "--map", "flat", "--format",
                                 "png", "--out", out});
  ASSERT_EQ(png.exit_code, 0) << png.output;
  EXPECT_TRUE(fs::exists(out + "/flat_v1_elevation.png"));
  CliResult csv = RunCli(procs, {"export", "--db", db, "--site", "lab", "--map", "flat", "--format",
                                 "csv", "--out", out});
  ASSERT_EQ(csv.exit_code, 0) << csv.output;
  CliResult diff =
      RunCli(procs, {"diff", "--db", db, "--site", "lab", "--map", "flat", "--map-b", "drawn"});
  EXPECT_EQ(diff.exit_code, 1) << diff.output;
  EXPECT_NE(diff.output.find("static"), std::string::npos);
}

TEST(MapstoreCliTest, ExportsNeverWriteOutsideTheTargetFolder) {
  ProcessSet procs(cairn::testing::PrivateLcmUrl());
  common::Layer occ;
  const std::string db = MakeDatabase(procs.dir(), &occ);
  const std::string out = procs.dir() + "/export";
  fs::create_directories(out);
  fs::create_symlink(procs.dir() + "/victim.pgm", out + "/flat_v1_static.pgm");
  CliResult through_link =
      RunCli(procs, {"export", "--db", db, "--site", "lab", "--map", "flat", "--out", out});
  EXPECT_EQ(through_link.exit_code, 1);
  EXPECT_NE(through_link.output.find("symlink"), std::string::npos) << through_link.output;
  EXPECT_FALSE(fs::exists(procs.dir() + "/victim.pgm"));
  CliResult stem = RunCli(procs, {"export", "--db", db, "--site", "lab", "--map", "flat", "--out",
                                  out, "--stem", "../escape"});
  EXPECT_EQ(stem.exit_code, 1);
  EXPECT_FALSE(fs::exists(procs.dir() + "/escape.yaml"));
  CliResult name = RunCli(procs, {"show", "--db", db, "--site", "lab", "--map", "../flat"});
  EXPECT_EQ(name.exit_code, 1);
  EXPECT_NE(name.output.find("INVALID_ARGUMENT"), std::string::npos) << name.output;
}

TEST(MapstoreCliTest, CheckRefusesForeignFilesAndFindsDamage) {
  ProcessSet procs(cairn::testing::PrivateLcmUrl());
  common::Layer occ;
  const std::string db = MakeDatabase(procs.dir(), &occ);
  CliResult ok = RunCli(procs, {"check", "--db", db});
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_NE(ok.output.find(": ok"), std::string::npos);

  const std::string text = procs.dir() + "/notes.db";
  std::ofstream(text) << "not a database at all, just some text\n" << std::string(4096, '#');
  CliResult foreign = RunCli(procs, {"check", "--db", text});
  EXPECT_EQ(foreign.exit_code, 1);
  EXPECT_NE(foreign.output.find("not a cairn map database"), std::string::npos) << foreign.output;
  CliResult list_foreign = RunCli(procs, {"list", "--db", text});
  EXPECT_EQ(list_foreign.exit_code, 1);

  // Damage one blob's stored bytes inside the file: check names the blob and fails.
  {
    auto store = SqliteMapStore::Open(db);
    ASSERT_TRUE(store.ok());
    const auto blobs = (*store)->BaseBlobBytes({"lab", "flat", 0});
    ASSERT_TRUE(blobs.ok());
    std::string victim = blobs->begin()->second;
    store->reset();
    std::string file = ReadAll(db);
    const size_t at = file.find(victim.substr(0, std::min<size_t>(victim.size(), 64)));
    ASSERT_NE(at, std::string::npos);
    file[at + victim.size() / 2] ^= 0x55;
    std::ofstream(db, std::ios::binary | std::ios::trunc) << file;
  }
  CliResult damaged = RunCli(procs, {"check", "--db", db});
  EXPECT_EQ(damaged.exit_code, 1) << damaged.output;
  EXPECT_NE(damaged.output.find("DAMAGED"), std::string::npos) << damaged.output;
  EXPECT_NE(damaged.output.find("blob"), std::string::npos) << damaged.output;
}

TEST(MapstoreCliTest, EveryCommandPrintsHelp) {
  ProcessSet procs(cairn::testing::PrivateLcmUrl());
  for (const char* command :
       {"list", "show", "export", "import", "share", "diff", "eval", "check", "vacuum", "migrate",
        "profiles", "put-profile", "delete", "audit", "places"}) {
    CliResult r = RunCli(procs, {command, "--help"});
    EXPECT_EQ(r.exit_code, 0) << command;
    EXPECT_NE(r.output.find(std::string("cairn-map ") + command), std::string::npos) << r.output;
  }
  CliResult top = RunCli(procs, {"--help"});
  EXPECT_EQ(top.exit_code, 0);
  // The formats come from the io registry: every registered one is listed.
  CliResult export_help = RunCli(procs, {"export", "--help"});
  for (const char* format : {"ros-raw", "png", "bt", "ot", "csv"}) {
    EXPECT_NE(export_help.output.find(std::string(format) + ":"), std::string::npos)
        << format << " in " << export_help.output;
    EXPECT_NE(top.output.find(format), std::string::npos) << format;
  }
  CliResult unknown = RunCli(procs, {"frobnicate"});
  EXPECT_EQ(unknown.exit_code, 2);
  CliResult store_help = RunCli(procs, {});
  EXPECT_EQ(store_help.exit_code, 2);
  ChildProcess& service = procs.StartRaw("cairn-mapstore", {BinPath("cairn-mapstore"), "--help"});
  auto status = service.WaitExit(10.0);
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(WEXITSTATUS(*status), 0);
  EXPECT_NE(service.Log().find("--db"), std::string::npos);
}

// Saves lab/<name>, 60 x 40 cells of 0.2 m whose heights are height_m(ix) (variance 1e-6 m^2),
// mapped with the pioneer3at, and stores the pioneer3at and rover profiles.
void SaveLabMapWithTwoProfiles(const std::string& db, const std::string& name,
                               const std::function<float(int)>& height_m) {
  auto store = SqliteMapStore::Open(db);
  ASSERT_TRUE(store.ok());
  MapSnapshot s = TerrainSnapshot("lab", name, 60, 40, 0.f);
  for (int iy = 0; iy < 40; ++iy) {
    for (int ix = 0; ix < 60; ++ix) {
      s.base.at("elevation")(ix, iy) = height_m(ix);
      s.base.at("elevation_variance")(ix, iy) = 1e-6f;
    }
  }
  ASSERT_TRUE((*store)->SaveMap(s, {"cli-test", 0, 0}).ok());
  ASSERT_TRUE((*store)->PutProfile(ShippedProfile("pioneer3at"), {"cli-test", 0, 0}).ok());
  ASSERT_TRUE((*store)->PutProfile(ShippedProfile("rover"), {"cli-test", 0, 0}).ok());
}

TEST(MapstoreCliTest, ShareAndDiffUnderTwoProfiles) {
  ProcessSet procs(cairn::testing::PrivateLcmUrl());
  const std::string db = procs.dir() + "/site.db";
  const double rise = std::tan(10.0 * M_PI / 180.0) * 0.2;
  SaveLabMapWithTwoProfiles(
      db, "hill", [&](int ix) { return static_cast<float>(std::clamp(ix - 15, 0, 25) * rise); });
  CliResult share = RunCli(
      procs, {"share", "--db", db, "--site", "lab", "--map", "hill", "--profile", "rover"}, 120.0);
  ASSERT_EQ(share.exit_code, 0) << share.output;
  EXPECT_NE(share.output.find("derived and cached"), std::string::npos) << share.output;
  CliResult diff = RunCli(procs,
                          {"diff", "--db", db, "--site", "lab", "--map", "hill", "--profile-a",
                           "pioneer3at", "--profile-b", "rover"},
                          120.0);
  EXPECT_EQ(diff.exit_code, 1) << diff.output;
  EXPECT_NE(diff.output.find("cost/pioneer3at"), std::string::npos) << diff.output;
  CliResult show = RunCli(procs, {"show", "--db", db, "--site", "lab", "--map", "hill"});
  EXPECT_EQ(show.exit_code, 0) << show.output;
  EXPECT_NE(show.output.find("1 cached derivations"), std::string::npos) << show.output;
}

// An 8 cm step across a stored map: the pioneer3at may drive down it and never up (3 cm step
// up), the rover crosses it both ways (8 cm up, 15 cm down). `share` lists that change, with the
// direction the pioneer3at may take.
TEST(MapstoreCliTest, ShareListsTheOneWayVerdictsThatChange) {
  ProcessSet procs(cairn::testing::PrivateLcmUrl());
  const std::string db = procs.dir() + "/site.db";
  SaveLabMapWithTwoProfiles(db, "terrace", [](int ix) { return ix < 30 ? 0.08f : 0.0f; });
  CliResult share = RunCli(
      procs, {"share", "--db", db, "--site", "lab", "--map", "terrace", "--profile", "rover"},
      120.0);
  ASSERT_EQ(share.exit_code, 0) << share.output;
  EXPECT_NE(share.output.find("1 obstacles change verdict from pioneer3at to rover"),
            std::string::npos)
      << share.output;
  EXPECT_NE(share.output.find("pioneer3at: one-way"), std::string::npos) << share.output;
  EXPECT_NE(share.output.find("crossable downwards only"), std::string::npos) << share.output;
  EXPECT_NE(share.output.find("rover: crossable"), std::string::npos) << share.output;
}

// The arena's 12 x 10 m at 0.1 m from (-0.5, -0.5), 130 x 110 cells.
common::GridGeometry ArenaGrid() {
  common::GridGeometry g;
  g.resolution_m = 0.1;
  g.size_x = 130;
  g.size_y = 110;
  g.origin = {-0.5, -0.5, 0.0};
  return g;
}

// Stores lab/arena whose occupancy is the arena's ground truth (100 on obstacles, 0 free) and
// whose elevation is the true ground + 2 cm on the free cells.
void SaveArenaFromTruth(const std::string& db) {
  const common::GridMap truth = sim::RasteriseGroundTruth(
      sim::SimPaths::InTree(CAIRN_SOURCE_DIR).WorldPath("arena"), ArenaGrid());
  MapSnapshot s;
  s.site = "lab";
  s.name = "arena";
  s.provenance.source_robot = "rover1";
  s.provenance.source_profile = "pioneer3at";
  s.provenance.code_version = "test";
  s.base = common::GridMap(ArenaGrid());
  common::Layer& occ = s.base.AddLayer(layers::kOccupancy);
  common::Layer& z = s.base.AddLayer(layers::kElevation);
  common::Layer& var = s.base.AddLayer(layers::kElevationVariance);
  const common::Layer& t = truth.at(sim::kTruthOccupiedLayer);
  const common::Layer& ground = truth.at(sim::kTruthGroundLayer);
  for (Eigen::Index i = 0; i < t.size(); ++i) {
    occ.data()[i] = t.data()[i] * 100.f;
    if (t.data()[i] == 0.f) {
      z.data()[i] = ground.data()[i] + 0.02f;
      var.data()[i] = 1e-4f;
    }
  }
  auto store = SqliteMapStore::Open(db);
  ASSERT_TRUE(store.ok());
  ASSERT_TRUE((*store)->SaveMap(s, {"cli-test", 0, 0}).ok());
}

TEST(MapstoreCliTest, EvalAMapMadeFromTheTruthScoresPerfectly) {
  ProcessSet procs(cairn::testing::PrivateLcmUrl());
  const std::string db = procs.dir() + "/site.db";
  SaveArenaFromTruth(db);
  CliResult table = RunCli(procs,
                           {"eval", "--db", db, "--site", "lab", "--map", "arena", "--world",
                            "arena", "--start", "6.05,3.05"},
                           120.0);
  ASSERT_EQ(table.exit_code, 0) << table.output;
  // The table's columns, one space apart.
  std::string text;
  for (char ch : table.output) {
    if (ch != ' ' || text.empty() || text.back() != ' ') text += ch;
  }
  for (const char* line :
       {"occupied precision 100.0%", "occupied recall 100.0%", "free precision 100.0%",
        "coverage 100.0%", "occupied IoU 100.0%", "double walls 0 ", "elevation error 0.020 m",
        "layer occupancy: 130 x 110 cells of 0.1 m"}) {
    EXPECT_NE(text.find(line), std::string::npos) << line << " in\n" << table.output;
  }
  CliResult json = RunCli(procs,
                          {"eval", "--db", db, "--site", "lab", "--map", "arena", "--world",
                           "arena", "--start", "6.05,3.05", "--json"},
                          120.0);
  ASSERT_EQ(json.exit_code, 0) << json.output;
  for (const char* field :
       {"\"occupied_precision\": 1,", "\"occupied_recall\": 1,", "\"free_precision\": 1,",
        "\"coverage\": 1,", "\"occupied_iou\": 1,", "\"double_wall_crossings\": 0,",
        "\"truth_cells\": 14300,", "\"mean_abs_m\": 0.02"}) {
    EXPECT_NE(json.output.find(field), std::string::npos) << field << " in\n" << json.output;
  }
  EXPECT_EQ(json.output.front(), '{') << json.output;
}

TEST(MapstoreCliTest, EvalFailsCleanly) {
  ProcessSet procs(cairn::testing::PrivateLcmUrl());
  const std::string db = procs.dir() + "/site.db";
  SaveArenaFromTruth(db);
  const std::vector<std::string> base = {"eval", "--db", db, "--site", "lab", "--map", "arena"};
  auto run = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    return RunCli(procs, args, 120.0);
  };
  CliResult world = run({"--world", "atlantis", "--start", "6,3"});
  EXPECT_EQ(world.exit_code, 1) << world.output;
  EXPECT_NE(world.output.find("unknown world 'atlantis'"), std::string::npos) << world.output;
  EXPECT_NE(world.output.find("arena"), std::string::npos) << world.output;  // the list
  CliResult file = run({"--world", procs.dir() + "/missing.xml", "--start", "6,3"});
  EXPECT_EQ(file.exit_code, 1) << file.output;
  EXPECT_NE(file.output.find("not found"), std::string::npos) << file.output;
  CliResult layer = run({"--world", "arena", "--start", "6,3", "--layer", "static"});
  EXPECT_EQ(layer.exit_code, 1) << layer.output;
  EXPECT_NE(layer.output.find("has no layer 'static'"), std::string::npos) << layer.output;
  CliResult outside = run({"--world", "arena", "--start", "40,3"});
  EXPECT_EQ(outside.exit_code, 1) << outside.output;
  EXPECT_NE(outside.output.find("outside"), std::string::npos) << outside.output;
  CliResult in_wall = run({"--world", "arena", "--start", "6.05,-0.05"});
  EXPECT_EQ(in_wall.exit_code, 1) << in_wall.output;
  EXPECT_NE(in_wall.output.find("not free"), std::string::npos) << in_wall.output;
  CliResult syntax = run({"--world", "arena", "--start", "six"});
  EXPECT_EQ(syntax.exit_code, 2) << syntax.output;
  CliResult no_world = run({"--start", "6,3"});
  EXPECT_EQ(no_world.exit_code, 2) << no_world.output;
  EXPECT_NE(no_world.output.find("--world"), std::string::npos) << no_world.output;
}

}  // namespace
}  // namespace cairn::mapstore::testing
