#include "mapstore/io/ros_map.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include <gtest/gtest.h>

#include "common/layers.h"
#include "mapstore/in_memory_map_store.h"
#include "mapstore/io/files.h"
#include "mapstore/map_transfer.h"
#include "tests/unit/mapstore/fake_deriver.h"
#include "tests/unit/mapstore/io/io_test_support.h"

namespace cairn::mapstore::io {
namespace {

using common::StatusCode;
using testing::Geometry;
using testing::Pattern;
using testing::TempDir;
using testing::WriteText;
namespace fs = std::filesystem;

TEST(RosMapTest, TrinaryRoundTripKeepsFreeOccupiedUnknown) {
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

TEST(RosMapTest, RawModeKeepsEveryValue) {
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

TEST(RosMapTest, ScaleModeFollowsMapServer) {
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

TEST(RosMapTest, HandDrawnMapsWithCommentsAsciiAndNegateLoad) {
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

TEST(RosMapTest, BadMapFilesAreRefusedWithAMessage) {
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

// Through the registry: "ros-raw" keeps the stored occupancy exactly, and reading the files
// back makes a new version with the same layer.
TEST(RosMapTest, ExportedAndImportedThroughTheRegistry) {
  InMemoryMapStore store;
  MapSnapshot s = mapstore::testing::SampleSnapshot("hall", 31, 17);
  s.base.AddLayer(layers::kStaticMap) = Pattern(31, 17);
  ASSERT_TRUE(store.SaveMap(s, {"unit", 0, 0}).ok());
  ExportOptions options;
  options.ref = {"lab", "hall", 0};
  options.format = "ros-raw";
  options.folder = TempDir();
  auto files = ExportMap(store, nullptr, options);
  ASSERT_TRUE(files.ok()) << files.status().ToString();
  ASSERT_EQ(files->size(), 2u);
  EXPECT_EQ(fs::path(files->at(0)).filename(), "hall_v1_static.yaml");
  ImportOptions import;
  import.path = files->at(0);
  import.site = "lab";
  import.name = "hall";
  import.layer = "static_copy";
  auto info = ImportMap(store, import, {"unit", 0, 0});
  ASSERT_TRUE(info.ok()) << info.status().ToString();
  auto back = store.LoadLayers({"lab", "hall", 2}, {});
  ASSERT_TRUE(back.ok());
  EXPECT_TRUE(mapstore::testing::SameLayer(back->at("static_copy"), s.base.at(layers::kStaticMap)));
  EXPECT_TRUE(back->HasLayer(layers::kElevation));  // the latest version's layers stay
  // A map without an occupancy layer says what to name.
  options.ref = {"lab", "hall", 0};
  options.format = "ros";
  ASSERT_TRUE(store.SaveMap(mapstore::testing::SampleSnapshot("bare"), {"unit", 0, 0}).ok());
  options.ref.name = "bare";
  auto refused = ExportMap(store, nullptr, options);
  EXPECT_EQ(refused.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(refused.status().message().find("has no occupancy layer"), std::string::npos);
}

}  // namespace
}  // namespace cairn::mapstore::io
