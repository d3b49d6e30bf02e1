#include "services/runtime/revolution_assembler.h"

#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

namespace cairn::runtime {
namespace {

TEST(SplitSliceTest, SlicesStayUnderLimitAndKeepEveryPoint) {
  common::LidarSlice whole;
  whole.revolution = 3;
  whole.azimuth_start_rad = 0.0;
  whole.azimuth_end_rad = 2 * M_PI;
  for (int i = 0; i < 57600; ++i)
    whole.points.push_back({float(i), 0.f, 0.f, 0.f, int16_t(i % 32)});
  auto slices = SplitSlice(whole, 64000);
  EXPECT_GE(slices.size(), 16u);
  size_t total = 0;
  for (size_t i = 0; i < slices.size(); ++i) {
    EXPECT_EQ(slices[i].slice_index, static_cast<int>(i));
    EXPECT_EQ(slices[i].slice_count, static_cast<int>(slices.size()));
    EXPECT_LE(slices[i].points.size() * kBytesPerLidarPoint + 512, 64000u);
    total += slices[i].points.size();
  }
  EXPECT_EQ(total, whole.points.size());
  EXPECT_EQ(slices.back().points.back().x_m, 57599.f);
}

common::LidarSlice Make(int64_t rev, int idx, int count, int points = 0) {
  common::LidarSlice s;
  s.robot = "r";
  s.revolution = rev;
  s.slice_index = idx;
  s.slice_count = count;
  s.points.resize(points);
  return s;
}

TEST(RevolutionAssemblerTest, CompletesAndReportsGaps) {
  RevolutionAssembler assembler;
  auto make = [](int64_t rev, int idx, int count) { return Make(rev, idx, count); };
  EXPECT_TRUE(assembler.OnSlice(make(1, 1, 3), 0).empty());
  EXPECT_TRUE(assembler.OnSlice(make(1, 0, 3), 0).empty());
  EXPECT_TRUE(assembler.OnSlice(make(1, 0, 3), 0).empty());  // duplicate ignored
  auto done = assembler.OnSlice(make(1, 2, 3), 0);
  ASSERT_EQ(done.size(), 1u);
  EXPECT_TRUE(done[0].complete());
  EXPECT_EQ(done[0].slices[0].slice_index, 0);
  // Revolution 2 loses slice 1; revolution 3 supersedes it.
  assembler.OnSlice(make(2, 0, 3), 0);
  assembler.OnSlice(make(2, 2, 3), 0);
  done = assembler.OnSlice(make(3, 0, 3), 0);
  ASSERT_EQ(done.size(), 1u);
  EXPECT_FALSE(done[0].complete());
  EXPECT_EQ(assembler.incomplete_revolutions(), 1);
  EXPECT_EQ(assembler.missing_slices(), 1);
}

// Issue 20: the assembler had no cap on slices, and kept a revolution numbered INT64_MAX (whose
// slices never complete it) forever, growing with every slice a peer sent for it.
TEST(RevolutionAssemblerTest, ARevolutionThatNeverCompletesExpiresAndIsBounded) {
  RevolutionLimits limits;
  limits.max_points_pending = 1000;
  limits.timeout_us = 2'000'000;
  RevolutionAssembler assembler(limits);
  const int64_t forever = std::numeric_limits<int64_t>::max();
  // The hostile revolution claims 4096 slices and sends many of them: what it holds stays
  // within the budget, and an honest slice pushes it out.
  for (int i = 0; i < 200; ++i) assembler.OnSlice(Make(forever, i, 4096, 10), 1000 * i);
  EXPECT_LE(assembler.pending_points(), 1000);
  EXPECT_GT(assembler.refused_slices(), 0);
  auto done = assembler.OnSlice(Make(7, 0, 2, 10), 300'000);
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].revolution, forever);
  EXPECT_FALSE(done[0].complete());
  done = assembler.OnSlice(Make(7, 1, 2, 10), 300'000);
  ASSERT_EQ(done.size(), 1u);
  EXPECT_TRUE(done[0].complete());

  // Within the budget, it waits beside the honest revolutions until its timeout.
  EXPECT_TRUE(assembler.OnSlice(Make(forever, 0, 4096, 10), 400'000).empty());
  EXPECT_TRUE(assembler.OnSlice(Make(8, 0, 2, 10), 500'000).empty());
  done = assembler.OnSlice(Make(8, 1, 2, 10), 500'000);
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].revolution, 8);
  done = assembler.OnSlice(Make(9, 0, 2, 10), 2'500'000);
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].revolution, forever);
  EXPECT_EQ(assembler.expired_revolutions(), 1);
  EXPECT_EQ(assembler.pending_points(), 10);
}

TEST(RevolutionAssemblerTest, SlicesBeyondTheLimitsAreRefusedAndChangeNothing) {
  RevolutionLimits limits;
  limits.max_slices_per_revolution = 64;
  limits.max_points_per_slice = 100;
  limits.max_pending_revolutions = 2;
  RevolutionAssembler assembler(limits);
  ASSERT_TRUE(assembler.OnSlice(Make(1, 0, 2, 5), 0).empty());
  EXPECT_TRUE(assembler.OnSlice(Make(1, 0, 65, 5), 0).empty());  // too many slices
  EXPECT_TRUE(assembler.OnSlice(Make(1, 1, 2, 101), 0).empty());  // too many points
  EXPECT_TRUE(assembler.OnSlice(Make(1, 1, 3, 5), 0).empty());   // disagrees with slice 0
  EXPECT_TRUE(assembler.OnSlice(Make(1, 3, 2, 5), 0).empty());   // index beyond the count
  EXPECT_EQ(assembler.refused_slices(), 4);
  EXPECT_EQ(assembler.pending_points(), 5);
  auto done = assembler.OnSlice(Make(1, 1, 2, 5), 0);
  ASSERT_EQ(done.size(), 1u);
  EXPECT_TRUE(done[0].complete());

  // Many robots' revolutions: the first to arrive is pushed out to make room.
  auto of = [](const std::string& robot, int64_t rev) {
    common::LidarSlice s = Make(rev, 0, 2, 1);
    s.robot = robot;
    return s;
  };
  EXPECT_TRUE(assembler.OnSlice(of("a", 1), 10).empty());
  EXPECT_TRUE(assembler.OnSlice(of("b", 1), 20).empty());
  done = assembler.OnSlice(of("c", 1), 30);
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].robot, "a");
}

}  // namespace
}  // namespace cairn::runtime
