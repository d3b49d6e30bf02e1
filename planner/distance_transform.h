#pragma once

#include <Eigen/Core>

/// @file
/// Exact Euclidean distance transform on a grid (Felzenszwalb and Huttenlocher, "Distance
/// Transforms of Sampled Functions", 2012): linear in the number of cells.

namespace cairn::planner {

/// Boolean mask over a grid, indexed (ix, iy) like common::Layer.
using GridMask = Eigen::Matrix<uint8_t, Eigen::Dynamic, Eigen::Dynamic>;

/// Distance in cells from every cell centre to the nearest cell centre where `mask` is set
/// (0 on the mask itself); +infinity everywhere when the mask is empty.
Eigen::MatrixXf DistanceTransform(const GridMask& mask);

}  // namespace cairn::planner
