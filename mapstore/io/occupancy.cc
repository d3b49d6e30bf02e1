#include "mapstore/io/occupancy.h"

#include <algorithm>
#include <cmath>

#include "common/layers.h"

namespace cairn::mapstore::io {

bool IsOccupancyLayer(const std::string& name) {
  return layers::IsCostLayer(name) || name == layers::kStaticMap || name == layers::kShortTerm ||
         name == layers::kLongTerm || name == layers::kFinal || name == "occupancy" ||
         name == layers::kSonarOccupancy;
}

common::Result<common::Layer> OccupancyPercent(const common::GridMap& map,
                                               const std::string& layer) {
  if (!map.HasLayer(layer)) return common::NotFoundError("no layer '" + layer + "'");
  const common::Layer& in = map.at(layer);
  common::Layer out(in.rows(), in.cols());
  if (layer == layers::kOccupancyLogOdds) {
    for (Eigen::Index i = 0; i < in.size(); ++i) {
      const float l = in.data()[i];
      out.data()[i] = std::isnan(l) ? common::kUnknown : 100.f / (1.f + std::exp(-l));
    }
    return out;
  }
  if (!IsOccupancyLayer(layer)) {
    return common::InvalidArgumentError("layer '" + layer +
                                        "' is not an occupancy or cost layer (export it as png)");
  }
  for (Eigen::Index i = 0; i < in.size(); ++i) {
    const float v = in.data()[i];
    out.data()[i] = std::isnan(v) ? common::kUnknown : std::clamp(v, 0.f, 100.f);
  }
  return out;
}

}  // namespace cairn::mapstore::io
