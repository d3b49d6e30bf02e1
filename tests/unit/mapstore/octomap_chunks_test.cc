#include "mapstore/octomap_chunks.h"

#include <gtest/gtest.h>

namespace cairn::mapstore {
namespace {

OctomapData Tree(size_t bytes) {
  OctomapData t;
  t.binary = false;
  t.resolution_m = 0.1;
  for (size_t i = 0; i < bytes; ++i) t.bytes.push_back(static_cast<char>(i * 31 + 7));
  return t;
}

TEST(OctomapChunksTest, SplitAndReassembledInAnyOrderGivesTheTreeBack) {
  const OctomapData tree = Tree(1000);
  const auto chunks = SplitOctomap(tree, 300);
  ASSERT_EQ(chunks.size(), 4u);
  EXPECT_EQ(chunks.back().size, 100u);
  OctomapAssembler dut;
  for (size_t i : {3u, 1u, 0u}) {
    EXPECT_TRUE(dut.Add(chunks[i]));
    EXPECT_FALSE(dut.complete().has_value());
  }
  EXPECT_TRUE(dut.Add(chunks[2]));
  ASSERT_TRUE(dut.complete().has_value());
  EXPECT_EQ(*dut.complete(), tree);
}

TEST(OctomapChunksTest, AnEmptyTreeIsOneChunk) {
  const auto chunks = SplitOctomap(Tree(0));
  ASSERT_EQ(chunks.size(), 1u);
  OctomapAssembler dut;
  EXPECT_TRUE(dut.Add(chunks[0]));
  ASSERT_TRUE(dut.complete().has_value());
  EXPECT_TRUE(dut.complete()->bytes.empty());
}

TEST(OctomapChunksTest, DamagedOrInconsistentChunksNeverMakeATree) {
  const OctomapData tree = Tree(500);
  auto chunks = SplitOctomap(tree, 200);
  std::string damaged(chunks[1].data, chunks[1].size);
  damaged[3] ^= 0x40;
  OctomapChunk bad = chunks[1];
  bad.data = damaged.data();
  OctomapAssembler dut;
  dut.Add(chunks[0]);
  dut.Add(bad);
  dut.Add(chunks[2]);
  EXPECT_FALSE(dut.complete().has_value());  // the checksum fails
  dut.Add(chunks[1]);                        // the good copy replaces it
  EXPECT_TRUE(dut.complete().has_value());

  OctomapChunk out_of_range = chunks[0];
  out_of_range.chunk_index = 7;
  EXPECT_FALSE(dut.Add(out_of_range));
  OctomapChunk too_big = chunks[0];
  too_big.total_bytes = OctomapAssembler::kMaxTotalBytes + 1;
  EXPECT_FALSE(dut.Add(too_big));
  OctomapChunk newer = chunks[0];
  newer.version = 2;
  EXPECT_TRUE(dut.Add(newer));  // another version starts over
  EXPECT_FALSE(dut.complete().has_value());
}

}  // namespace
}  // namespace cairn::mapstore
