#pragma once

#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/types.h"
#include <Eigen/Core>

/// @file
/// GridMap: named float layers over one rectangular grid (grid_map's data model without ROS).
///
/// Geometry. The grid has `size_x` × `size_y` square cells of `resolution_m`. The map frame is
/// placed in the world by `origin`: (origin.x_m, origin.y_m) is the world position of the
/// minimum corner of cell (0, 0) and origin.yaw_rad the rotation of the grid's x axis.
/// Cell (ix, iy) covers map-frame [ix·res, (ix+1)·res) × [iy·res, (iy+1)·res). World to cell
/// uses floor, never truncation, so negative coordinates fall in the right cell.
///
/// Storage. A layer is an Eigen column-major matrix indexed (ix, iy): x runs fastest in memory,
/// from the minimum corner. `layer.data()[ix + iy * size_x]` is cell (ix, iy). This is the order
/// of every tile, blob and message in the product.
///
/// NaN means unknown.

namespace cairn::common {

using Layer = Eigen::MatrixXf;  ///< (ix, iy), column-major: x fastest.

inline constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();

struct CellIndex {
  int ix{0};
  int iy{0};
  bool operator==(const CellIndex& o) const { return ix == o.ix && iy == o.iy; }
  bool operator!=(const CellIndex& o) const { return !(*this == o); }
};

struct GridGeometry {
  double resolution_m{0.2};
  int size_x{0};
  int size_y{0};
  Pose2 origin;  ///< world pose of the minimum corner of cell (0, 0)

  double length_x_m() const { return size_x * resolution_m; }
  double length_y_m() const { return size_y * resolution_m; }
  int64_t num_cells() const { return static_cast<int64_t>(size_x) * size_y; }
  bool operator==(const GridGeometry& o) const {
    return resolution_m == o.resolution_m && size_x == o.size_x && size_y == o.size_y &&
           origin == o.origin;
  }
  bool operator!=(const GridGeometry& o) const { return !(*this == o); }
  /// @throws std::invalid_argument for a non-positive or non-finite resolution or size.
  void Validate() const;

  /// Cell containing a world position, or nullopt outside the grid.
  std::optional<CellIndex> IndexOf(const Vector2& world_m) const;
  /// Cell coordinates as reals (map frame divided by resolution), unbounded.
  Vector2 ContinuousIndexOf(const Vector2& world_m) const;
  /// World position of a cell's centre.
  Vector2 CenterOf(const CellIndex& cell) const;
  bool Contains(const CellIndex& cell) const {
    return cell.ix >= 0 && cell.iy >= 0 && cell.ix < size_x && cell.iy < size_y;
  }
  int64_t LinearIndex(const CellIndex& cell) const {
    return cell.ix + static_cast<int64_t>(cell.iy) * size_x;
  }
};

/// Named float layers over one GridGeometry. Copyable and movable (a value type).
class GridMap {
 public:
  GridMap() = default;
  /// @throws std::invalid_argument if the geometry is invalid.
  explicit GridMap(const GridGeometry& geometry);

  const GridGeometry& geometry() const { return geometry_; }
  int size_x() const { return geometry_.size_x; }
  int size_y() const { return geometry_.size_y; }
  double resolution_m() const { return geometry_.resolution_m; }

  /// Adds (or resets) a layer filled with `fill` (NaN by default).
  Layer& AddLayer(const std::string& name, float fill = kUnknown);
  /// Adds (or replaces) a layer with the given cells.
  /// @throws std::invalid_argument when they are not size_x x size_y.
  Layer& AddLayer(const std::string& name, Layer&& cells);
  bool HasLayer(const std::string& name) const { return layers_.count(name) > 0; }
  /// @throws std::out_of_range naming the layer if it does not exist.
  Layer& at(const std::string& name);
  const Layer& at(const std::string& name) const;
  void RemoveLayer(const std::string& name) { layers_.erase(name); }
  std::vector<std::string> layer_names() const;

  std::optional<CellIndex> IndexOf(const Vector2& world_m) const {
    return geometry_.IndexOf(world_m);
  }
  Vector2 CenterOf(const CellIndex& cell) const { return geometry_.CenterOf(cell); }
  bool Contains(const CellIndex& cell) const { return geometry_.Contains(cell); }

  /// Value of a layer at a world position; nullopt outside the map or when unknown.
  std::optional<float> ValueAt(const std::string& layer, const Vector2& world_m) const;

  bool operator==(const GridMap& other) const;

 private:
  GridGeometry geometry_;
  std::map<std::string, Layer> layers_;
};

}  // namespace cairn::common
