#include "planner/occupancy_cost.h"

#include <algorithm>
#include <cmath>

#include "common/check.h"

namespace cairn::planner {

const char* MapEncodingName(MapEncoding encoding) {
  return encoding == MapEncoding::kOccupancy ? "occupancy" : "cost";
}

MapEncoding MapEncodingFromName(const std::string& name) {
  if (name == "cost") return MapEncoding::kCost;
  if (name == "occupancy") return MapEncoding::kOccupancy;
  CAIRN_THROW_UNLESS(false, "unknown map encoding '" << name << "' (cost, occupancy)");
  return MapEncoding::kCost;
}

void OccupancyCostParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(free_threshold_og) && free_threshold_og >= 0.0f,
                     "free_threshold_og must lie in [0, 100), got " << free_threshold_og);
  CAIRN_THROW_UNLESS(std::isfinite(occupied_threshold_og) && occupied_threshold_og <= 100.0f,
                     "occupied_threshold_og must lie in (0, 100], got " << occupied_threshold_og);
  CAIRN_THROW_UNLESS(free_threshold_og < occupied_threshold_og,
                     "free_threshold_og (" << free_threshold_og
                                           << ") must be below occupied_threshold_og ("
                                           << occupied_threshold_og << ")");
}

float OccupancyToCost(float occupancy_og, const OccupancyCostParams& params, float lethal_cost) {
  // NaN and the negative values (-1 and anything else below 0) are unknown.
  if (!(occupancy_og >= 0.0f)) return common::kUnknown;
  if (occupancy_og >= params.occupied_threshold_og) return lethal_cost;
  if (occupancy_og <= params.free_threshold_og) return 0.0f;
  const float fraction = (occupancy_og - params.free_threshold_og) /
                         (params.occupied_threshold_og - params.free_threshold_og);
  // In (0, lethal_cost) by the strict inequalities above; the clamp guards float rounding.
  return std::min(fraction * lethal_cost, std::nextafter(lethal_cost, 0.0f));
}

common::Layer OccupancyToCostLayer(const common::Layer& occupancy_og,
                                   const OccupancyCostParams& params, float lethal_cost) {
  params.Validate();
  CAIRN_THROW_UNLESS(std::isfinite(lethal_cost) && lethal_cost > 0.0f,
                     "lethal_cost must be positive, got " << lethal_cost);
  common::Layer cost(occupancy_og.rows(), occupancy_og.cols());
  const float* in = occupancy_og.data();
  float* out = cost.data();
  for (Eigen::Index i = 0; i < occupancy_og.size(); ++i) {
    out[i] = OccupancyToCost(in[i], params, lethal_cost);
  }
  return cost;
}

}  // namespace cairn::planner
