#include "mapstore/io/files.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include <gtest/gtest.h>

#include "mapstore/io/ros_map.h"
#include "tests/unit/mapstore/io/io_test_support.h"

namespace cairn::mapstore::io {
namespace {

using common::StatusCode;
using testing::Geometry;
using testing::Pattern;
using testing::TempDir;
namespace fs = std::filesystem;

TEST(FilesTest, WritersStayInTheirFolder) {
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

TEST(FilesTest, RequestPathsStayBelowTheRoot) {
  const std::string root = TempDir() + "/root";
  auto inside = PathBelow(root, "exports/today");
  ASSERT_TRUE(inside.ok()) << inside.status().ToString();
  EXPECT_EQ(fs::path(*inside), fs::weakly_canonical(root + "/exports/today"));
  for (const char* escape : {"..", "../x", "/etc", "a/../../b"}) {
    EXPECT_EQ(PathBelow(root, escape).status().code(), StatusCode::kInvalidArgument) << escape;
  }
  EXPECT_EQ(PathBelow(root, std::string("a\0b", 3)).status().code(), StatusCode::kInvalidArgument);
  // A symlink to a folder beside the root (not outside the build tree: the build's include
  // check walks it).
  const std::string elsewhere = fs::path(root).parent_path().string() + "/elsewhere";
  fs::create_directories(elsewhere);
  fs::create_symlink(elsewhere, root + "/out");
  EXPECT_EQ(PathBelow(root, "out/x").status().code(), StatusCode::kInvalidArgument);
}

TEST(FilesTest, ShortestDecimalReadsBackExactly) {
  for (double v : {0.1, 1.0 / 3.0, -7.76, 1e-9, 0.0}) {
    EXPECT_EQ(std::strtod(ShortestDecimal(v).c_str(), nullptr), v);
  }
  EXPECT_EQ(ShortestDecimal(0.05), "0.05");
  EXPECT_EQ(ShortestDecimal(std::nan("")), "nan");
}

}  // namespace
}  // namespace cairn::mapstore::io
