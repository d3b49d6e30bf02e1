#include "services/mapping/mapper_layer.h"

#include <algorithm>
#include <cstdio>
#include <fstream>

namespace cairn::mapping {
namespace {

std::string FileNameOf(const std::string& layer) {
  std::string s = layer;
  std::replace(s.begin(), s.end(), '/', '_');
  return s + ".f32";
}

common::Status WriteLayer(const std::string& path, const common::Layer& layer) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return common::UnavailableError("cannot write " + path);
  out.write(reinterpret_cast<const char*>(layer.data()),
            static_cast<std::streamsize>(layer.size() * sizeof(float)));
  return out ? common::Status::Ok() : common::UnavailableError("write failed: " + path);
}

std::string Num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

}  // namespace

common::Status WriteGridSection(const std::string& dir, const std::string& section,
                                const common::GridMap& map, const std::vector<std::string>& names,
                                std::ostream& yaml) {
  const common::GridGeometry& g = map.geometry();
  yaml << section << ":\n"
       << "  resolution_m: " << Num(g.resolution_m) << "\n"
       << "  size_x: " << g.size_x << "\n"
       << "  size_y: " << g.size_y << "\n"
       << "  origin: [" << Num(g.origin.x_m) << ", " << Num(g.origin.y_m) << ", "
       << Num(g.origin.yaw_rad) << "]\n"
       << "  layers:\n";
  for (const auto& name : names) {
    const common::Status s = WriteLayer(dir + "/" + FileNameOf(name), map.at(name));
    if (!s.ok()) return s;
    yaml << "    - {name: \"" << name << "\", file: " << FileNameOf(name) << "}\n";
  }
  return common::Status::Ok();
}

common::Status MapperLayer::WriteOutputs(const std::string& dir, std::ostream& yaml) const {
  std::vector<std::string> names;
  for (const GridOutput& out : GridOutputs()) {
    if (out.written) names.push_back(out.name);
  }
  if (names.empty()) return common::Status::Ok();
  const std::optional<common::GridMap> map = ExportGrids();
  if (!map) return common::Status::Ok();
  return WriteGridSection(dir, name(), *map, names, yaml);
}

}  // namespace cairn::mapping
