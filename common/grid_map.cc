#include "common/grid_map.h"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "common/check.h"

namespace cairn::common {

void GridGeometry::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(resolution_m) && resolution_m > 0.0,
                     "grid resolution must be positive, got " << resolution_m);
  CAIRN_THROW_UNLESS(size_x >= 0 && size_y >= 0,
                     "grid size must not be negative, got " << size_x << " x " << size_y);
  CAIRN_THROW_UNLESS(
      std::isfinite(origin.x_m) && std::isfinite(origin.y_m) && std::isfinite(origin.yaw_rad),
      "grid origin must be finite");
}

Vector2 GridGeometry::ContinuousIndexOf(const Vector2& world_m) const {
  const double dx = world_m.x() - origin.x_m;
  const double dy = world_m.y() - origin.y_m;
  if (origin.yaw_rad == 0.0) return {dx / resolution_m, dy / resolution_m};
  const double c = std::cos(origin.yaw_rad), s = std::sin(origin.yaw_rad);
  return {(c * dx + s * dy) / resolution_m, (-s * dx + c * dy) / resolution_m};
}

std::optional<CellIndex> GridGeometry::IndexOf(const Vector2& world_m) const {
  const Vector2 c = ContinuousIndexOf(world_m);
  if (!std::isfinite(c.x()) || !std::isfinite(c.y())) return std::nullopt;
  const double fx = std::floor(c.x()), fy = std::floor(c.y());
  if (fx < 0.0 || fy < 0.0 || fx >= size_x || fy >= size_y) return std::nullopt;
  return CellIndex{static_cast<int>(fx), static_cast<int>(fy)};
}

Vector2 GridGeometry::CenterOf(const CellIndex& cell) const {
  const double mx = (cell.ix + 0.5) * resolution_m;
  const double my = (cell.iy + 0.5) * resolution_m;
  if (origin.yaw_rad == 0.0) return {origin.x_m + mx, origin.y_m + my};
  return origin.Transform({mx, my});
}

GridMap::GridMap(const GridGeometry& geometry) : geometry_(geometry) { geometry_.Validate(); }

Layer& GridMap::AddLayer(const std::string& name, float fill) {
  CAIRN_THROW_UNLESS(!name.empty(), "a layer needs a name");
  Layer& layer = layers_[name];
  layer.setConstant(geometry_.size_x, geometry_.size_y, fill);
  return layer;
}

Layer& GridMap::AddLayer(const std::string& name, Layer&& cells) {
  CAIRN_THROW_UNLESS(!name.empty(), "a layer needs a name");
  CAIRN_THROW_UNLESS(cells.rows() == geometry_.size_x && cells.cols() == geometry_.size_y,
                     "layer '" << name << "' has " << cells.rows() << " x " << cells.cols()
                               << " cells, the grid " << geometry_.size_x << " x "
                               << geometry_.size_y);
  Layer& layer = layers_[name];
  layer = std::move(cells);
  return layer;
}

Layer& GridMap::at(const std::string& name) {
  auto it = layers_.find(name);
  if (it == layers_.end()) throw std::out_of_range("grid map has no layer '" + name + "'");
  return it->second;
}

const Layer& GridMap::at(const std::string& name) const {
  auto it = layers_.find(name);
  if (it == layers_.end()) throw std::out_of_range("grid map has no layer '" + name + "'");
  return it->second;
}

std::vector<std::string> GridMap::layer_names() const {
  std::vector<std::string> names;
  names.reserve(layers_.size());
  for (const auto& [name, layer] : layers_) names.push_back(name);
  return names;
}

std::optional<float> GridMap::ValueAt(const std::string& layer, const Vector2& world_m) const {
  const auto cell = IndexOf(world_m);
  if (!cell) return std::nullopt;
  const float v = at(layer)(cell->ix, cell->iy);
  if (std::isnan(v)) return std::nullopt;
  return v;
}

bool GridMap::operator==(const GridMap& other) const {
  if (geometry_ != other.geometry_ || layers_.size() != other.layers_.size()) return false;
  for (const auto& [name, layer] : layers_) {
    auto it = other.layers_.find(name);
    if (it == other.layers_.end()) return false;
    const Layer& b = it->second;
    // Bitwise equality, so that NaN == NaN (unknown equals unknown).
    if (layer.size() != b.size() ||
        std::memcmp(layer.data(), b.data(), sizeof(float) * layer.size()) != 0) {
      return false;
    }
  }
  return true;
}

}  // namespace cairn::common
