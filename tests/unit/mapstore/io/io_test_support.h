#pragma once

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "common/grid_map.h"

// Shared by the file format tests: a fresh folder per test and small sample layers.

namespace cairn::mapstore::io::testing {

namespace fs = std::filesystem;

inline std::string TempDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::path(CAIRN_BINARY_DIR) / "test-tmp" /
                       (std::string(info->test_suite_name()) + "." + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

inline void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// An asymmetric occupancy pattern (catches flips and transpositions): free, occupied, graded
// and unknown cells.
inline common::Layer Pattern(int w, int h) {
  common::Layer l(w, h);
  for (int iy = 0; iy < h; ++iy) {
    for (int ix = 0; ix < w; ++ix) {
      const int k = (ix * 7 + iy * 3) % 5;
      l(ix, iy) = k == 0 ? 0.f : k == 1 ? 100.f : k == 2 ? common::kUnknown : k == 3 ? 42.f : 0.f;
    }
  }
  l(w - 1, 0) = 100.f;  // a marker in the bottom-right corner
  l(0, h - 1) = 0.f;
  return l;
}

inline common::GridGeometry Geometry(int w, int h) {
  common::GridGeometry g;
  g.resolution_m = 0.05;
  g.size_x = w;
  g.size_y = h;
  g.origin = {-7.76, -9.4, 0.0};
  return g;
}

}  // namespace cairn::mapstore::io::testing
