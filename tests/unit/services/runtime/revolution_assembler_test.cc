#include "services/runtime/revolution_assembler.h"

#include <cmath>

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

TEST(RevolutionAssemblerTest, CompletesAndReportsGaps) {
  RevolutionAssembler assembler;
  auto make = [](int64_t rev, int idx, int count) {
    common::LidarSlice s;
    s.robot = "r";
    s.revolution = rev;
    s.slice_index = idx;
    s.slice_count = count;
    return s;
  };
  EXPECT_TRUE(assembler.OnSlice(make(1, 1, 3)).empty());
  EXPECT_TRUE(assembler.OnSlice(make(1, 0, 3)).empty());
  EXPECT_TRUE(assembler.OnSlice(make(1, 0, 3)).empty());  // duplicate ignored
  auto done = assembler.OnSlice(make(1, 2, 3));
  ASSERT_EQ(done.size(), 1u);
  EXPECT_TRUE(done[0].complete());
  EXPECT_EQ(done[0].slices[0].slice_index, 0);
  // Revolution 2 loses slice 1; revolution 3 supersedes it.
  assembler.OnSlice(make(2, 0, 3));
  assembler.OnSlice(make(2, 2, 3));
  done = assembler.OnSlice(make(3, 0, 3));
  ASSERT_EQ(done.size(), 1u);
  EXPECT_FALSE(done[0].complete());
  EXPECT_EQ(assembler.incomplete_revolutions(), 1);
  EXPECT_EQ(assembler.missing_slices(), 1);
}

}  // namespace
}  // namespace cairn::runtime
