#include "mapstore/io/octomap_files.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "mapstore/in_memory_map_store.h"
#include "mapstore/map_transfer.h"
#include "tests/unit/mapstore/fake_deriver.h"
#include "tests/unit/mapstore/io/io_test_support.h"

namespace cairn::mapstore::io {
namespace {

using common::StatusCode;
using testing::TempDir;
using testing::WriteText;

TEST(OctomapFilesTest, OctomapFilesConvertBetweenBinaryAndFull) {
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

TEST(OctomapFilesTest, AMapWithoutAnOctomapHasNoneToExport) {
  InMemoryMapStore store;
  ASSERT_TRUE(store.SaveMap(mapstore::testing::SampleSnapshot("hall"), {"unit", 0, 0}).ok());
  ExportOptions options;
  options.ref = {"lab", "hall", 0};
  options.folder = TempDir();
  for (const char* format : {"bt", "ot"}) {
    options.format = format;
    EXPECT_EQ(ExportMap(store, nullptr, options).status().code(), StatusCode::kNotFound);
  }
}

}  // namespace
}  // namespace cairn::mapstore::io
