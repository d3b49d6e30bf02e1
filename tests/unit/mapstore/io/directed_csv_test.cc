#include "mapstore/io/directed_csv.h"

#include <cmath>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>

#include "common/layers.h"
#include "mapstore/io/files.h"
#include "tests/unit/mapstore/io/io_test_support.h"

namespace cairn::mapstore::io {
namespace {

using testing::TempDir;

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// Cells that refuse nothing (0) or are unknown (NaN) are left out; a one-way cell lists the
// headings it refuses in the world frame (the grid's origin turned by 90 deg here); 255 and a
// value that is not a whole mask are "all", as the planner reads them.
TEST(DirectedCsvTest, OneRowPerRefusingCellWithItsWorldHeadings) {
  common::GridGeometry g;
  g.resolution_m = 0.5;
  g.size_x = 3;
  g.size_y = 2;
  g.origin = {1.0, 2.0, M_PI / 2};
  common::GridMap map(g);
  common::Layer& d = map.AddLayer(layers::DirectedLayer("p"));
  d.setZero();
  d(0, 0) = std::nanf("");
  d(1, 0) = 4.f;  // bit 2: +y in the grid, 180 deg in the world
  d(2, 0) = 255.f;
  d(0, 1) = 3.5f;
  d(2, 1) = static_cast<float>((1u << 0) | (1u << 7));  // grid 0 and 315 deg: world 90 and 45
  const std::string dir = TempDir();
  auto path = WriteDirectedCsv(dir, "dir", map, layers::DirectedLayer("p"));
  ASSERT_TRUE(path.ok()) << path.status().message();
  auto text = ReadFile(*path);
  ASSERT_TRUE(text.ok());
  const auto lines = Lines(*text);
  ASSERT_EQ(lines.size(), 5u) << *text;
  EXPECT_EQ(lines[0], "x_m,y_m,mask,refused_headings_deg");
  const common::Vector2 c10 = map.CenterOf({1, 0});
  char expect[96];
  std::snprintf(expect, sizeof(expect), "%.3f,%.3f,4,180", c10.x(), c10.y());
  EXPECT_EQ(lines[1], expect);
  EXPECT_NE(lines[2].find(",255,all"), std::string::npos) << lines[2];
  EXPECT_NE(lines[3].find(",255,all"), std::string::npos) << lines[3];
  EXPECT_NE(lines[4].find(",129,90;45"), std::string::npos) << lines[4];
  EXPECT_FALSE(WriteDirectedCsv(dir, "none", map, "directed/other").ok());
}

// An unseen drop (the mapper's mark 256) keeps its own value and says what it is.
TEST(DirectedCsvTest, AnUnseenDropIsListedAsSuch) {
  common::GridGeometry g;
  g.resolution_m = 0.5;
  g.size_x = 2;
  g.size_y = 1;
  common::GridMap map(g);
  common::Layer& d = map.AddLayer(layers::DirectedLayer("p"));
  d.setZero();
  d(1, 0) = layers::kUnseenDrop;
  auto path = WriteDirectedCsv(TempDir(), "unseen", map, layers::DirectedLayer("p"));
  ASSERT_TRUE(path.ok()) << path.status().message();
  auto text = ReadFile(*path);
  ASSERT_TRUE(text.ok());
  const auto lines = Lines(*text);
  ASSERT_EQ(lines.size(), 2u) << *text;
  EXPECT_NE(lines[1].find(",256,all (unseen drop)"), std::string::npos) << lines[1];
}

}  // namespace
}  // namespace cairn::mapstore::io
