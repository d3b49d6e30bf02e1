#include "mapstore/io/directed_csv.h"

#include <cmath>
#include <cstdio>
#include <vector>

#include "common/layers.h"
#include "mapstore/io/files.h"
#include "mapstore/io/format_registry.h"

namespace cairn::mapstore::io {

using common::Result;

namespace {

// The refused headings of a mask, world frame, in whole degrees where they are whole.
std::string RefusedHeadings(unsigned mask, double origin_yaw_rad) {
  if (mask == 255u) return "all";
  std::string out;
  for (int b = 0; b < layers::kHeadingBins; ++b) {
    if (!(mask & (1u << b))) continue;
    double deg = std::fmod(b * 45.0 + origin_yaw_rad * 180.0 / M_PI, 360.0);
    if (deg < 0) deg += 360.0;
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%s%.4g", out.empty() ? "" : ";", deg);
    out += buf;
  }
  return out;
}

Result<std::vector<std::string>> ExportDirected(const ExportContext& ctx) {
  if (ctx.options().profile.empty()) {
    return common::InvalidArgumentError(
        "the directed export needs a profile (--profile): it writes directed/<profile>");
  }
  const std::string layer = layers::DirectedLayer(ctx.options().profile);
  auto map = ctx.LoadLayer(layer);
  if (!map.ok()) return map.status();
  auto path = WriteDirectedCsv(ctx.options().folder, ctx.Stem("directed"), *map, layer);
  if (!path.ok()) return path.status();
  return std::vector<std::string>{*path};
}

}  // namespace

Result<std::string> WriteDirectedCsv(const std::string& folder, const std::string& stem,
                                     const common::GridMap& map, const std::string& layer) {
  if (!map.HasLayer(layer)) return common::InvalidArgumentError("no layer '" + layer + "'");
  auto path = OutputPath(folder, stem, ".csv");
  if (!path.ok()) return path.status();
  const common::Layer& d = map.at(layer);
  std::string out = "x_m,y_m,mask,refused_headings_deg\n";
  char buf[96];
  for (int iy = 0; iy < map.size_y(); ++iy) {
    for (int ix = 0; ix < map.size_x(); ++ix) {
      const float v = d(ix, iy);
      if (std::isnan(v) || v == 0.f) continue;
      const common::Vector2 c = map.CenterOf({ix, iy});
      if (v == layers::kUnseenDrop) {
        std::snprintf(buf, sizeof(buf), "%.3f,%.3f,256,all (unseen drop)\n", c.x(), c.y());
        out += buf;
        continue;
      }
      // Any other value that is not a whole number in [0, 255] reads as 255, as the planner
      // reads it.
      const unsigned mask =
          (v > 0.f && v <= 255.f && v == std::round(v)) ? static_cast<unsigned>(v) : 255u;
      std::snprintf(buf, sizeof(buf), "%.3f,%.3f,%u,", c.x(), c.y(), mask);
      out += buf;
      out += RefusedHeadings(mask, map.geometry().origin.yaw_rad) + "\n";
    }
  }
  const common::Status s = WriteFileAtomically(*path, out);
  if (!s.ok()) return s;
  return *path;
}

void RegisterDirectedCsvFormats(FormatRegistry* registry) {
  registry->AddExporter(
      {"directed",
       "CSV of the profile's one-way and blocked cells with the headings they refuse (needs "
       "--profile)",
       ExportDirected});
}

}  // namespace cairn::mapstore::io
