#include "mapstore/io/png.h"

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
