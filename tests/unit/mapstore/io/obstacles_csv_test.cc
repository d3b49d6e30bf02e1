#include "mapstore/io/obstacles_csv.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "mapstore/in_memory_map_store.h"
#include "mapstore/map_transfer.h"
#include "tests/support/sample_obstacles.h"
#include "tests/unit/mapstore/fake_deriver.h"
#include "tests/unit/mapstore/io/io_test_support.h"

namespace cairn::mapstore::io {
namespace {

using common::StatusCode;
using testing::TempDir;
using testing::WriteText;
namespace fs = std::filesystem;

TEST(ObstaclesCsvTest, ObstacleCsvRoundTripsExactly) {
  const std::string dir = TempDir();
  common::ObstacleRegistry r;
  common::Obstacle o;
  o.id = 5;
  o.kind = common::ObstacleKind::kRamp;
  o.centroid_m = {1.0 / 3.0, -2.5};
  o.outline_m = {{0.1, 0.2}, {1e-9, 3.75}, {2, 2}};
  o.slope_rad = 0.17453292519943295;
  o.height_m = 0.2;
  o.depth_m = std::nan("");
  o.num_cells = 33;
  o.downhill_heading_rad = -2.0943951023931953;
  o.verdicts = {{"pioneer3at", "abc", false, "slope 10.0 deg > 8.0 deg; \"steep\" | really"},
                {"rover", "def", true, ""}};
  common::Obstacle wall;
  wall.id = 6;
  wall.kind = common::ObstacleKind::kWallOrObject;
  r.obstacles = {o, wall};
  auto path = WriteObstaclesCsv(dir, "obstacles", r);
  ASSERT_TRUE(path.ok()) << path.status().ToString();
  auto back = ReadObstaclesCsv(*path);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  ASSERT_EQ(back->obstacles.size(), 2u);
  const common::Obstacle& b = back->obstacles[0];
  EXPECT_EQ(b.id, 5);
  EXPECT_EQ(b.kind, common::ObstacleKind::kRamp);
  EXPECT_EQ(b.centroid_m, o.centroid_m);
  EXPECT_EQ(b.outline_m, o.outline_m);
  EXPECT_EQ(b.slope_rad, o.slope_rad);
  EXPECT_TRUE(std::isnan(b.depth_m));
  EXPECT_EQ(b.num_cells, 33);
  EXPECT_EQ(b.downhill_heading_rad, o.downhill_heading_rad);
  EXPECT_TRUE(std::isnan(back->obstacles[1].downhill_heading_rad));
  EXPECT_EQ(b.verdicts, o.verdicts);
  EXPECT_TRUE(back->obstacles[1].verdicts.empty());
  WriteText(dir + "/bad.csv", "id,kind\n1,ramp\n");
  EXPECT_EQ(ReadObstaclesCsv(dir + "/bad.csv").status().code(), StatusCode::kInvalidArgument);
}

// A terrace's parts follow it as rows of their own (part_of its id) and come back in order; a
// part row with no terrace before it is refused with its line.
TEST(ObstaclesCsvTest, ATerraceAndItsPartsRoundTrip) {
  const std::string dir = TempDir();
  common::ObstacleRegistry r;
  common::Obstacle wall;
  wall.id = 8;
  wall.kind = common::ObstacleKind::kWallOrObject;
  r.obstacles = {cairn::testing::SampleTerrace(), wall};
  auto path = WriteObstaclesCsv(dir, "terrace", r);
  ASSERT_TRUE(path.ok()) << path.status().ToString();
  auto back = ReadObstaclesCsv(*path);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  ASSERT_EQ(back->obstacles.size(), 2u);
  const common::Obstacle& t = back->obstacles[0];
  ASSERT_EQ(t.parts.size(), 2u);
  for (size_t k = 0; k < 2; ++k) {
    const common::ObstaclePart& want = r.obstacles[0].parts[k];
    EXPECT_EQ(t.parts[k].kind, want.kind);
    EXPECT_EQ(t.parts[k].centroid_m, want.centroid_m);
    EXPECT_EQ(t.parts[k].outline_m, want.outline_m);
    EXPECT_EQ(t.parts[k].heading_in_rad, want.heading_in_rad);
    EXPECT_EQ(t.parts[k].verdicts, want.verdicts);
  }
  EXPECT_EQ(t.verdicts, r.obstacles[0].verdicts);
  EXPECT_TRUE(back->obstacles[1].parts.empty());
  // The same rows with the wall first: its parts would follow the wall.
  std::ifstream in(*path);
  std::string header, terrace_row, part1, part2, wall_row;
  std::getline(in, header);
  std::getline(in, terrace_row);
  std::getline(in, part1);
  std::getline(in, part2);
  std::getline(in, wall_row);
  WriteText(dir + "/orphan.csv", header + "\n" + wall_row + "\n" + part1 + "\n");
  auto orphan = ReadObstaclesCsv(dir + "/orphan.csv");
  EXPECT_EQ(orphan.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(orphan.status().message().find(":3:"), std::string::npos) << orphan.status().message();
  WriteText(dir + "/bare.csv", header + "\n" + terrace_row + "\n");
  EXPECT_EQ(ReadObstaclesCsv(dir + "/bare.csv").status().code(), StatusCode::kInvalidArgument);
}

TEST(ObstaclesCsvTest, ExportedAndImportedThroughTheRegistry) {
  InMemoryMapStore store;
  ImportOptions import;
  import.site = "lab";
  import.name = "hall";
  const std::string dir = TempDir();
  WriteText(dir + "/early.csv", "x");
  import.path = dir + "/early.csv";
  auto early = ImportMap(store, import, {"unit", 0, 0});
  EXPECT_EQ(early.status().code(), StatusCode::kNotFound);  // obstacles need a map first
  EXPECT_EQ(early.status().message(),
            "no map 'lab/hall' to import .csv data into (import a grid map first)");

  ASSERT_TRUE(store.SaveMap(mapstore::testing::SampleSnapshot("hall"), {"unit", 0, 0}).ok());
  ExportOptions options;
  options.ref = {"lab", "hall", 0};
  options.format = "csv";
  options.folder = dir;
  auto files = ExportMap(store, nullptr, options);
  ASSERT_TRUE(files.ok()) << files.status().ToString();
  EXPECT_EQ(fs::path(files->front()).filename(), "hall_v1_obstacles.csv");
  import.path = files->front();
  auto info = ImportMap(store, import, {"unit", 0, 0});
  ASSERT_TRUE(info.ok()) << info.status().ToString();
  EXPECT_EQ(store.LoadObstacles({"lab", "hall", 2}).value().obstacles.size(), 2u);
}

}  // namespace
}  // namespace cairn::mapstore::io
