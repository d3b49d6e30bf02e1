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

// Issue 20: chunk counts and bytes were unbounded: chunks of a tree that claims a huge count
// (and never completes) grew the assembler with every chunk a peer sent.
TEST(OctomapChunksTest, WhatChunksMakeItHoldIsBoundedByTheTreeTheyDeclare) {
  const OctomapData tree = Tree(1000);
  auto chunks = SplitOctomap(tree, 300);
  OctomapAssembler dut;
  ASSERT_TRUE(dut.Add(chunks[0]));
  // Chunks of the same tree whose bytes would exceed its declared size.
  const std::string big(900, 'x');
  OctomapChunk over = chunks[1];
  over.data = big.data();
  over.size = big.size();
  EXPECT_FALSE(dut.Add(over));
  EXPECT_EQ(dut.held_bytes(), 300);
  // A chunk that disagrees with the tree's size or checksum.
  OctomapChunk other_total = chunks[1];
  other_total.total_bytes = 5000;
  EXPECT_FALSE(dut.Add(other_total));
  OctomapChunk other_crc = chunks[1];
  other_crc.checksum ^= 1;
  EXPECT_FALSE(dut.Add(other_crc));
  // A count beyond the limit, or a chunk larger than its whole tree.
  OctomapChunk many = chunks[0];
  many.version = 2;
  many.chunk_count = OctomapAssembler::kMaxChunks + 1;
  EXPECT_FALSE(dut.Add(many));
  OctomapChunk larger = chunks[0];
  larger.version = 2;
  larger.total_bytes = 10;
  EXPECT_FALSE(dut.Add(larger));
  // A hostile tree claiming 60,000 chunks of the largest size, sent one chunk after another: it
  // holds no more than its declared total.
  OctomapAssembler bomb;
  const std::string chunk_bytes(192 * 1024, 'y');
  int64_t refused = 0;
  for (int i = 0; i < 3000; ++i) {
    OctomapChunk c;
    c.version = 9;
    c.chunk_index = i;
    c.chunk_count = 60000;
    c.total_bytes = 64 << 20;
    c.data = chunk_bytes.data();
    c.size = chunk_bytes.size();
    refused += bomb.Add(c) ? 0 : 1;
  }
  EXPECT_LE(bomb.held_bytes(), int64_t{64} << 20);
  EXPECT_GT(refused, 0);
  // The honest tree still completes.
  for (const auto& c : chunks) EXPECT_TRUE(dut.Add(c));
  ASSERT_TRUE(dut.complete().has_value());
  EXPECT_EQ(*dut.complete(), tree);
}

}  // namespace
}  // namespace cairn::mapstore
