#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/status.h"

/// @file
/// An RGB canvas with a 5x7 bitmap font, lines and frames, encoded as PNG (libpng): what the
/// PNG export draws maps and legends on. Internal to mapstore/io/.

namespace cairn::mapstore::io {

struct Rgb {
  uint8_t r, g, b;
};

/// An RGB canvas with text drawing.
class Canvas {
 public:
  Canvas(int width, int height) : w_(width), h_(height), pixels_(width * height * 3, 255) {}
  int width() const { return w_; }
  int height() const { return h_; }
  void Set(int x, int y, Rgb c) {
    if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
    uint8_t* p = &pixels_[(static_cast<size_t>(y) * w_ + x) * 3];
    p[0] = c.r;
    p[1] = c.g;
    p[2] = c.b;
  }
  void Fill(int x0, int y0, int w, int h, Rgb c) {  // inline: a render calls it per cell
    for (int y = y0; y < y0 + h; ++y) {
      for (int x = x0; x < x0 + w; ++x) Set(x, y, c);
    }
  }
  void Frame(int x0, int y0, int w, int h, Rgb c);
  /// Draws text (upper-cased; unknown characters as blanks); returns the end x.
  int Text(int x, int y, const std::string& text, Rgb c);
  /// A line of the given thickness (Bresenham, square pen).
  void Line(int x0, int y0, int x1, int y1, Rgb c, int thickness = 1);
  const std::vector<uint8_t>& pixels() const { return pixels_; }

 private:
  int w_, h_;
  std::vector<uint8_t> pixels_;
};

inline constexpr Rgb kUnknownColour{196, 212, 232};
inline constexpr Rgb kBlack{0, 0, 0};

/// Occupancy colours: white free, black lethal, amber to dark red graded, pale blue unknown.
Rgb OccupancyColour(float percent);
/// A perceptual blue-green-yellow ramp (viridis-like) for continuous layers, t in [0, 1].
Rgb RampColour(float t);
/// The canvas as PNG bytes.
common::Result<std::string> EncodePng(const Canvas& canvas);

}  // namespace cairn::mapstore::io
