#include "mapstore/map_io.h"

#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <png.h>

#include "common/layers.h"

namespace cairn::mapstore::io {
namespace {

namespace fs = std::filesystem;
using common::StatusCode;

std::string TempDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::path(CAIRN_BINARY_DIR) / "test-tmp" /
                       (std::string(info->test_suite_name()) + "." + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// An asymmetric occupancy pattern (catches flips and transpositions): free, occupied, graded
// and unknown cells.
common::Layer Pattern(int w, int h) {
  common::Layer l(w, h);
  for (int iy = 0; iy < h; ++iy) {
    for (int ix = 0; ix < w; ++ix) {
      const int k = (ix * 7 + iy * 3) % 5;
      l(ix, iy) = k == 0 ? 0.f : k == 1 ? 100.f : k == 2 ? common::kUnknown : k == 3 ? 42.f : 0.f;
    }
  }
  l(w - 1, 0) = 100.f;  // a marker in the bottom-right corner
  l(0, h - 1) = 0.f;
  return l;
}

common::GridGeometry Geometry(int w, int h) {
  common::GridGeometry g;
  g.resolution_m = 0.05;
  g.size_x = w;
  g.size_y = h;
  g.origin = {-7.76, -9.4, 0.0};
  return g;
}

TEST(MapIoTest, TrinaryRoundTripKeepsFreeOccupiedUnknown) {
  const std::string dir = TempDir();
  const common::Layer l = Pattern(31, 17);
  auto files = WriteRosMap(dir, "flat", Geometry(31, 17), l);
  ASSERT_TRUE(files.ok()) << files.status().ToString();
  auto back = ReadRosMap(dir + "/flat.yaml");
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_EQ(back->geometry, Geometry(31, 17));
  EXPECT_EQ(back->options.mode, PgmMode::kTrinary);
  for (int iy = 0; iy < 17; ++iy) {
    for (int ix = 0; ix < 31; ++ix) {
      const float v = l(ix, iy), r = back->occupancy(ix, iy);
      if (std::isnan(v) || v == 42.f) {
        EXPECT_TRUE(std::isnan(r)) << ix << "," << iy;  // graded is neither free nor occupied
      } else {
        EXPECT_EQ(r, v) << ix << "," << iy;
      }
    }
  }
  // map_server conventions in the file itself: the first image row is the top of the map.
  const std::string pgm = ReadFile(dir + "/flat.pgm").value();
  const size_t data = pgm.size() - 31 * 17;
  EXPECT_EQ(static_cast<uint8_t>(pgm[data]), 254);          // (0, 16): free
  EXPECT_EQ(static_cast<uint8_t>(pgm[pgm.size() - 1]), 0);  // (30, 0): occupied
}

TEST(MapIoTest, RawModeKeepsEveryValue) {
  const std::string dir = TempDir();
  common::Layer l(10, 3);
  for (int i = 0; i < 30; ++i) l.data()[i] = static_cast<float>(i * 3 % 101);
  l(4, 1) = common::kUnknown;
  RosMapOptions raw;
  raw.mode = PgmMode::kRaw;
  ASSERT_TRUE(WriteRosMap(dir, "raw", Geometry(10, 3), l, raw).ok());
  auto back = ReadRosMap(dir + "/raw.yaml");
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  for (int i = 0; i < 30; ++i) {
    if (std::isnan(l.data()[i])) {
      EXPECT_TRUE(std::isnan(back->occupancy.data()[i]));
    } else {
      EXPECT_EQ(back->occupancy.data()[i], l.data()[i]);
    }
  }
}

TEST(MapIoTest, ScaleModeFollowsMapServer) {
  const std::string dir = TempDir();
  common::Layer l(3, 1);
  l << 0.f, 100.f, 42.f;
  RosMapOptions scale;
  scale.mode = PgmMode::kScale;
  ASSERT_TRUE(WriteRosMap(dir, "scale", Geometry(3, 1), l, scale).ok());
  auto back = ReadRosMap(dir + "/scale.yaml");
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->occupancy(0, 0), 0.f);
  EXPECT_EQ(back->occupancy(1, 0), 100.f);
  // p = 0.42 lies between the thresholds: 99 * (0.42 - 0.196) / (0.65 - 0.196) ~ 48.
  EXPECT_NEAR(back->occupancy(2, 0), 48.f, 1.f);
}

TEST(MapIoTest, HandDrawnMapsWithCommentsAsciiAndNegateLoad) {
  const std::string dir = TempDir();
  // An ASCII PGM as an editor writes it, 3 x 2, with a comment.
  WriteText(dir + "/drawn.pgm", "P2\n# drawn in GIMP\n3 2\n255\n0 254 205\n254 0 254\n");
  WriteText(dir + "/drawn.yaml",
            "image: drawn.pgm\nresolution: 0.1\norigin: [1.0, 2.0, 0.0]\nnegate: 0\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.196\n");
  auto map = ReadRosMap(dir + "/drawn.yaml");
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  // Row 0 of the image is the top (iy = 1).
  EXPECT_EQ(map->occupancy(0, 1), 100.f);
  EXPECT_EQ(map->occupancy(1, 1), 0.f);
  EXPECT_TRUE(std::isnan(map->occupancy(2, 1)));
  EXPECT_EQ(map->occupancy(1, 0), 100.f);
  WriteText(dir + "/negated.yaml",
            "image: drawn.pgm\nresolution: 0.1\norigin: [1.0, 2.0, 0.0]\nnegate: 1\n");
  auto negated = ReadRosMap(dir + "/negated.yaml");
  ASSERT_TRUE(negated.ok());
  EXPECT_EQ(negated->occupancy(0, 1), 0.f);
  EXPECT_EQ(negated->occupancy(1, 1), 100.f);
}

TEST(MapIoTest, BadMapFilesAreRefusedWithAMessage) {
  const std::string dir = TempDir();
  WriteText(dir + "/ok.pgm", "P5\n1 1\n255\n\xfe");
  WriteText(dir + "/typo.yaml", "image: ok.pgm\nresolution: 0.1\norigin: [0, 0, 0]\nmdoe: raw\n");
  auto typo = ReadRosMap(dir + "/typo.yaml");
  EXPECT_EQ(typo.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(typo.status().message().find("mdoe"), std::string::npos);
  EXPECT_NE(typo.status().message().find(":4"), std::string::npos) << typo.status().message();
  WriteText(dir + "/escape.yaml", "image: ../../etc/passwd\nresolution: 0.1\norigin: [0, 0, 0]\n");
  EXPECT_EQ(ReadRosMap(dir + "/escape.yaml").status().code(), StatusCode::kInvalidArgument);
  WriteText(dir + "/absolute.yaml", "image: /etc/passwd\nresolution: 0.1\norigin: [0, 0, 0]\n");
  EXPECT_EQ(ReadRosMap(dir + "/absolute.yaml").status().code(), StatusCode::kInvalidArgument);
  WriteText(dir + "/short.pgm", "P5\n4 4\n255\nab");
  WriteText(dir + "/short.yaml", "image: short.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n");
  auto short_pgm = ReadRosMap(dir + "/short.yaml");
  EXPECT_EQ(short_pgm.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(short_pgm.status().message().find("truncated"), std::string::npos);
  WriteText(dir + "/png.yaml", "image: ok.pgm\nresolution: -1\norigin: [0, 0, 0]\n");
  EXPECT_EQ(ReadRosMap(dir + "/png.yaml").status().code(), StatusCode::kInvalidArgument);
  WriteText(dir + "/origin.yaml", "image: ok.pgm\nresolution: 0.1\norigin: [0, 0]\n");
  EXPECT_EQ(ReadRosMap(dir + "/origin.yaml").status().code(), StatusCode::kInvalidArgument);
}

TEST(MapIoTest, WritersStayInTheirFolder) {
  const std::string dir = TempDir();
  EXPECT_EQ(SafeOutputPath(dir, "../evil.pgm").status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(SafeOutputPath(dir, "a/b.pgm").status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(SafeOutputPath(dir, "..").status().code(), StatusCode::kInvalidArgument);
  fs::create_symlink("/tmp/cairn-elsewhere.pgm", dir + "/link.pgm");
  EXPECT_EQ(SafeOutputPath(dir, "link.pgm").status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(WriteRosMap(dir, "../up", Geometry(2, 2), Pattern(2, 2)).status().code(),
            StatusCode::kInvalidArgument);
  EXPECT_FALSE(fs::exists(fs::path(dir).parent_path() / "up.pgm"));
  auto ok = SafeOutputPath(dir + "/new/sub", "map.pgm");
  ASSERT_TRUE(ok.ok());
  EXPECT_EQ(fs::path(*ok).parent_path(), fs::canonical(dir + "/new/sub"));
}

TEST(MapIoTest, PngRenderHasTheMapAndALegend) {
  const std::string dir = TempDir();
  common::GridMap map(Geometry(40, 20));
  map.AddLayer("cost/rover") = Pattern(40, 20);
  common::Layer& e = map.AddLayer(layers::kElevation);
  for (int i = 0; i < e.size(); ++i) e.data()[i] = 0.01f * i;
  for (const std::string layer : {"cost/rover", "elevation"}) {
    auto path = WritePng(dir, layer == "elevation" ? "elevation" : "cost", map, layer);
    ASSERT_TRUE(path.ok()) << path.status().ToString();
    FILE* f = std::fopen(path->c_str(), "rb");
    ASSERT_NE(f, nullptr);
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png_create_info_struct(png);
    png_init_io(png, f);
    png_read_info(png, info);
    const int w = png_get_image_width(png, info), h = png_get_image_height(png, info);
    png_destroy_read_struct(&png, &info, nullptr);
    std::fclose(f);
    // 40 x 20 cells at 8 px per cell (320 / 40), plus the legend below.
    EXPECT_EQ(w, 320);
    EXPECT_GT(h, 160);
  }
  EXPECT_EQ(WritePng(dir, "x", map, "missing").status().code(), StatusCode::kNotFound);
}

TEST(MapIoTest, ObstacleCsvRoundTripsExactly) {
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
  EXPECT_EQ(b.verdicts, o.verdicts);
  EXPECT_TRUE(back->obstacles[1].verdicts.empty());
  WriteText(dir + "/bad.csv", "id,kind\n1,ramp\n");
  EXPECT_EQ(ReadObstaclesCsv(dir + "/bad.csv").status().code(), StatusCode::kInvalidArgument);
}

TEST(MapIoTest, OctomapFilesConvertBetweenBinaryAndFull) {
  const std::string dir = TempDir();
  octomap::OcTree tree(0.1);
  for (int i = 0; i < 20; ++i) tree.updateNode(octomap::point3d(i * 0.1f, 0.5f, 0.3f), true);
  tree.updateNode(octomap::point3d(0.f, 0.f, 0.f), false);
  std::ostringstream bt;
  ASSERT_TRUE(tree.writeBinary(bt));
  const OctomapData stored{true, 0.1, bt.str()};
  auto ot_path = WriteOctomap(dir, "tree", stored, false);
  ASSERT_TRUE(ot_path.ok()) << ot_path.status().ToString();
  auto ot = ReadOctomap(*ot_path);
  ASSERT_TRUE(ot.ok()) << ot.status().ToString();
  EXPECT_FALSE(ot->binary);
  EXPECT_DOUBLE_EQ(ot->resolution_m, 0.1);
  auto bt_path = WriteOctomap(dir, "tree", *ot, true);
  ASSERT_TRUE(bt_path.ok());
  auto again = ReadOctomap(*bt_path);
  ASSERT_TRUE(again.ok());
  octomap::OcTree round(0.1);
  std::istringstream in(again->bytes);
  ASSERT_TRUE(round.readBinary(in));
  EXPECT_EQ(round.getNumLeafNodes(), tree.getNumLeafNodes());
  ASSERT_NE(round.search(0.5, 0.5, 0.3), nullptr);
  EXPECT_TRUE(round.isNodeOccupied(round.search(0.5, 0.5, 0.3)));
  WriteText(dir + "/junk.bt", "not a tree");
  EXPECT_EQ(ReadOctomap(dir + "/junk.bt").status().code(), StatusCode::kInvalidArgument);
}

TEST(MapIoTest, OccupancyPercentConvertsLogOddsAndRefusesElevation) {
  common::GridMap map(Geometry(2, 1));
  map.AddLayer(layers::kOccupancyLogOdds) << 0.f, 2.f;
  map.AddLayer(layers::kElevation, 1.f);
  auto p = OccupancyPercent(map, layers::kOccupancyLogOdds);
  ASSERT_TRUE(p.ok());
  EXPECT_FLOAT_EQ((*p)(0, 0), 50.f);
  EXPECT_NEAR((*p)(1, 0), 88.08f, 0.01f);
  EXPECT_EQ(OccupancyPercent(map, layers::kElevation).status().code(),
            StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace cairn::mapstore::io
