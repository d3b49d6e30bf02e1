#include "mapstore/io/png.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>

#include <gtest/gtest.h>
#include <png.h>

#include "common/layers.h"
#include "mapstore/in_memory_map_store.h"
#include "mapstore/map_transfer.h"
#include "tests/unit/mapstore/fake_deriver.h"
#include "tests/unit/mapstore/io/io_test_support.h"

namespace cairn::mapstore::io {
namespace {

using common::StatusCode;
using testing::Geometry;
using testing::Pattern;
using testing::TempDir;
namespace fs = std::filesystem;

TEST(PngTest, PngRenderHasTheMapAndALegend) {
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

// Reads an RGB PNG's pixels.
std::vector<uint8_t> ReadRgb(const std::string& path, int* w, int* h) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return {};
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_init_io(png, f);
  png_read_info(png, info);
  *w = static_cast<int>(png_get_image_width(png, info));
  *h = static_cast<int>(png_get_image_height(png, info));
  std::vector<uint8_t> rgb(static_cast<size_t>(*w) * *h * 3);
  std::vector<png_bytep> rows(*h);
  for (int y = 0; y < *h; ++y) rows[y] = rgb.data() + static_cast<size_t>(y) * *w * 3;
  png_read_image(png, rows.data());
  png_destroy_read_struct(&png, &info, nullptr);
  std::fclose(f);
  return rgb;
}

TEST(PngTest, MarkersAreDrawnWhereTheyStand) {
  const std::string dir = TempDir();
  common::GridMap map(Geometry(40, 20));
  map.AddLayer("cost/rover") = Pattern(40, 20);
  PngOverlay overlay;
  // The centre of cell (10, 5): 8 px per cell, rows drawn from the top.
  const common::Vector2 at = map.CenterOf({10, 5});
  overlay.markers.push_back({at, "1"});
  auto path = WritePng(dir, "marked", map, "cost/rover", overlay);
  ASSERT_TRUE(path.ok()) << path.status().ToString();
  int w = 0, h = 0;
  const std::vector<uint8_t> rgb = ReadRgb(*path, &w, &h);
  ASSERT_GE(w, 320);  // 8 px per cell (the legend may be wider)
  ASSERT_GT(h, 160);
  const int cx = 10 * 8 + 4, cy = (20 - 5) * 8 - 4;
  auto pixel = [&](int x, int y) {
    const uint8_t* p = &rgb[(static_cast<size_t>(y) * w + x) * 3];
    return std::array<int, 3>{p[0], p[1], p[2]};
  };
  EXPECT_EQ(pixel(cx, cy), (std::array<int, 3>{255, 255, 255}));  // the square's white inside
  EXPECT_EQ(pixel(cx - 4, cy), (std::array<int, 3>{0, 0, 0}));    // its black rim
  EXPECT_EQ(pixel(cx + 4, cy + 4), (std::array<int, 3>{0, 0, 0}));
}

TEST(PngTest, ExportedThroughTheRegistryWithTheElevationByDefault) {
  InMemoryMapStore store;
  ASSERT_TRUE(store.SaveMap(mapstore::testing::SampleSnapshot("hall"), {"unit", 0, 0}).ok());
  ExportOptions options;
  options.ref = {"lab", "hall", 0};
  options.format = "png";
  options.folder = TempDir();
  auto files = ExportMap(store, nullptr, options);
  ASSERT_TRUE(files.ok()) << files.status().ToString();
  ASSERT_EQ(files->size(), 1u);
  EXPECT_EQ(fs::path(files->front()).filename(), "hall_v1_elevation.png");
  options.layer = "no_such_layer";
  EXPECT_EQ(ExportMap(store, nullptr, options).status().code(), StatusCode::kNotFound);
}

}  // namespace
}  // namespace cairn::mapstore::io
