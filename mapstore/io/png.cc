#include "mapstore/io/png.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "common/layers.h"
#include "mapstore/io/files.h"
#include "mapstore/io/format_registry.h"
#include "mapstore/io/occupancy.h"
#include "mapstore/io/png_canvas.h"
#include "mapstore/names.h"

namespace cairn::mapstore::io {

using common::Result;
using common::Status;

namespace {

constexpr Rgb kPath{20, 90, 230}, kCrossable{0, 150, 60}, kBlocked{215, 25, 30},
    kNoVerdict{90, 90, 90};

// A layer as drawn: its values (occupancy in percent for occupancy layers) and their range.
struct Rendered {
  common::Layer values;
  bool occupancy{false};
  float lo{std::numeric_limits<float>::infinity()};
  float hi{-std::numeric_limits<float>::infinity()};
  int scale{1};  // pixels per cell side
};

Result<Rendered> RenderValues(const common::GridMap& map, const std::string& layer) {
  Rendered r;
  r.occupancy = IsOccupancyLayer(layer) || layer == layers::kOccupancyLogOdds;
  r.values = map.at(layer);
  if (r.occupancy) {
    auto percent = OccupancyPercent(map, layer);
    if (!percent.ok()) return percent.status();
    r.values = *percent;
  }
  for (Eigen::Index i = 0; i < r.values.size(); ++i) {
    const float v = r.values.data()[i];
    if (std::isnan(v)) continue;
    r.lo = std::min(r.lo, v);
    r.hi = std::max(r.hi, v);
  }
  return r;
}

void DrawCells(const Rendered& r, Canvas* canvas) {
  // Locals, not r's fields: the canvas writes bytes, which may alias anything.
  const common::Layer& values = r.values;
  const bool occupancy = r.occupancy;
  const float lo = r.lo, hi = r.hi;
  const int scale = r.scale;
  const int w = static_cast<int>(values.rows()), h = static_cast<int>(values.cols());
  for (int iy = 0; iy < h; ++iy) {
    for (int ix = 0; ix < w; ++ix) {
      const float v = values(ix, iy);
      Rgb c;
      if (occupancy) {
        c = OccupancyColour(v);
      } else if (std::isnan(v)) {
        c = kUnknownColour;
      } else {
        c = RampColour(hi > lo ? (v - lo) / (hi - lo) : 0.5f);
      }
      canvas->Fill(ix * scale, (h - 1 - iy) * scale, scale, scale, c);
    }
  }
}

// Obstacles (outline and label) and the path, in world coordinates.
void DrawOverlay(const common::GridMap& map, const PngOverlay& overlay, int scale, Canvas* canvas) {
  const int h = map.size_y();
  auto to_pixel = [&](const common::Vector2& p) {
    const common::Vector2 c = map.geometry().ContinuousIndexOf(p);
    return std::make_pair(static_cast<int>(std::lround(c.x() * scale)),
                          static_cast<int>(std::lround((h - c.y()) * scale)));
  };
  // An outline in its verdict's colour (grey without one for the overlay's profile).
  auto draw = [&](const std::vector<common::Vector2>& outline, const common::ObstacleVerdict* v,
                  int width) {
    const Rgb colour = v == nullptr ? kNoVerdict : (v->crossable ? kCrossable : kBlocked);
    for (size_t i = 0; i < outline.size(); ++i) {
      const auto a = to_pixel(outline[i]);
      const auto b = to_pixel(outline[(i + 1) % outline.size()]);
      canvas->Line(a.first, a.second, b.first, b.second, colour, width);
    }
    return colour;
  };
  for (const auto& o : overlay.obstacles) {
    const Rgb colour = draw(o.outline_m, o.VerdictFor(overlay.verdict_profile), 2);
    // A terrace's parts, thin, each in its own verdict's colour.
    for (const auto& p : o.parts) draw(p.outline_m, p.VerdictFor(overlay.verdict_profile), 1);
    std::string kind = common::ObstacleKindName(o.kind);
    for (auto& ch : kind) ch = ch == '_' ? ' ' : ch;
    const auto c = to_pixel(o.centroid_m);
    const std::string label = std::to_string(o.id) + " " + kind;
    canvas->Fill(c.first - 1, c.second - 1, static_cast<int>(label.size()) * 6 + 2, 9,
                 {255, 255, 255});
    canvas->Text(c.first, c.second, label, colour);
  }
  for (size_t i = 1; i < overlay.path_m.size(); ++i) {
    const auto a = to_pixel(overlay.path_m[i - 1]);
    const auto b = to_pixel(overlay.path_m[i]);
    canvas->Line(a.first, a.second, b.first, b.second, kPath, 3);
  }
  for (const auto& m : overlay.markers) {
    const auto c = to_pixel(m.position_m);
    canvas->Fill(c.first - 4, c.second - 4, 9, 9, kBlack);
    canvas->Fill(c.first - 2, c.second - 2, 5, 5, {255, 255, 255});
    if (!m.label.empty()) {
      canvas->Fill(c.first + 6, c.second - 4, static_cast<int>(m.label.size()) * 6 + 2, 9,
                   {255, 255, 255});
      canvas->Text(c.first + 7, c.second - 3, m.label, kBlack);
    }
  }
  if (!overlay.path_m.empty()) {
    const auto s = to_pixel(overlay.path_m.front());
    const auto e = to_pixel(overlay.path_m.back());
    canvas->Fill(s.first - 4, s.second - 4, 9, 9, kPath);
    canvas->Frame(e.first - 6, e.second - 6, 13, 13, kPath);
    canvas->Frame(e.first - 5, e.second - 5, 11, 11, kPath);
  }
}

// Swatches of a legend row, left to right.
class LegendRow {
 public:
  LegendRow(Canvas* canvas, int x, int y) : canvas_(canvas), x_(x), y_(y) {}
  void Swatch(Rgb c, const std::string& label) {
    canvas_->Fill(x_, y_, 12, 12, c);
    canvas_->Frame(x_, y_, 12, 12, kBlack);
    x_ = canvas_->Text(x_ + 16, y_ + 3, label, kBlack) + 10;
  }
  // A colour bar from lo to hi.
  void Ramp(float lo, float hi) {
    char lo_text[32], hi_text[32];
    std::snprintf(lo_text, sizeof(lo_text), "%.3g", std::isfinite(lo) ? lo : 0.f);
    std::snprintf(hi_text, sizeof(hi_text), "%.3g", std::isfinite(hi) ? hi : 0.f);
    x_ = canvas_->Text(x_, y_ + 3, lo_text, kBlack) + 4;
    for (int i = 0; i < 100; ++i) canvas_->Fill(x_ + i, y_, 1, 12, RampColour(i / 99.f));
    canvas_->Frame(x_, y_, 100, 12, kBlack);
    x_ = canvas_->Text(x_ + 104, y_ + 3, hi_text, kBlack) + 10;
  }

 private:
  Canvas* canvas_;
  int x_;
  int y_;
};

// Legend: the layer and resolution, swatches or a colour bar, the overlay's keys, the caption.
void DrawLegend(const common::GridMap& map, const std::string& layer, const Rendered& r,
                const PngOverlay& overlay, Canvas* canvas) {
  const int y0 = map.size_y() * r.scale + 6;
  char title[160];
  std::snprintf(title, sizeof(title), "%s  %.3g M/CELL  %dX%d", layer.c_str(), map.resolution_m(),
                map.size_x(), map.size_y());
  canvas->Text(4, y0, title, kBlack);
  const int y1 = y0 + 14;
  LegendRow row(canvas, 4, y1);
  if (r.occupancy) {
    row.Swatch(OccupancyColour(0.f), "FREE");
    row.Swatch(OccupancyColour(50.f), "1-99");
    row.Swatch(OccupancyColour(100.f), "LETHAL");
  } else {
    row.Ramp(r.lo, r.hi);
  }
  row.Swatch(kUnknownColour, "UNKNOWN");
  int y2 = y1 + 20;
  if (!overlay.path_m.empty() || !overlay.obstacles.empty() || !overlay.markers.empty()) {
    LegendRow keys(canvas, 4, y2);
    if (!overlay.path_m.empty()) keys.Swatch(kPath, "DRIVEN PATH");
    if (!overlay.markers.empty()) keys.Swatch(kBlack, "VIEW POINTS");
    if (!overlay.obstacles.empty()) {
      keys.Swatch(kCrossable, "CROSSABLE" + (overlay.verdict_profile.empty()
                                                 ? std::string()
                                                 : " BY " + overlay.verdict_profile));
      keys.Swatch(kBlocked, "NOT CROSSABLE");
    }
    y2 += 18;
  }
  if (!overlay.caption.empty()) {
    canvas->Text(4, y2, overlay.caption, kBlack);
    y2 += 12;
  }
  canvas->Text(4, y2, "CAIRN MAP STORE", {90, 90, 90});
}

Result<std::vector<std::string>> ExportPng(const ExportContext& ctx) {
  auto layer = ctx.ChooseLayer({layers::kElevation}, /*or_first_layer=*/true);
  if (!layer.ok()) return layer.status();
  auto map = ctx.LoadLayer(*layer);
  if (!map.ok()) return map.status();
  auto path = WritePng(ctx.options().folder, ctx.Stem(*layer), *map, *layer);
  if (!path.ok()) return path.status();
  return std::vector<std::string>{*path};
}

}  // namespace

Result<std::string> WritePng(const std::string& folder, const std::string& stem,
                             const common::GridMap& map, const std::string& layer) {
  PngOverlay none;
  none.min_pixels = 320;
  return WritePng(folder, stem, map, layer, none);
}

Result<std::string> WritePng(const std::string& folder, const std::string& stem,
                             const common::GridMap& map, const std::string& layer,
                             const PngOverlay& overlay) {
  Status s = ValidateName("file stem", stem);
  if (!s.ok()) return s;
  if (!map.HasLayer(layer)) return common::NotFoundError("no layer '" + layer + "'");
  auto path = SafeOutputPath(folder, stem + ".png");
  if (!path.ok()) return path.status();
  auto rendered = RenderValues(map, layer);
  if (!rendered.ok()) return rendered.status();
  const int w = map.size_x(), h = map.size_y();
  rendered->scale = std::clamp(overlay.min_pixels / std::max(1, std::max(w, h)), 1, 8);
  const bool has_overlay =
      !overlay.path_m.empty() || !overlay.obstacles.empty() || !overlay.markers.empty();
  const int legend_h = has_overlay || !overlay.caption.empty() ? 92 : 52;
  const int canvas_w = std::max(w * rendered->scale, has_overlay ? 560 : 300);
  Canvas canvas(canvas_w, h * rendered->scale + legend_h);
  DrawCells(*rendered, &canvas);
  DrawOverlay(map, overlay, rendered->scale, &canvas);
  DrawLegend(map, layer, *rendered, overlay, &canvas);
  auto png = EncodePng(canvas);
  if (!png.ok()) return png.status();
  if (!(s = WriteFileAtomically(*path, *png)).ok()) return s;
  return *path;
}

void RegisterPngFormats(FormatRegistry* registry) {
  registry->AddExporter({"png", "PNG render of a layer with a legend", ExportPng});
}

}  // namespace cairn::mapstore::io
