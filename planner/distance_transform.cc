#include "planner/distance_transform.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace cairn::planner {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
// Larger than any squared distance on a grid we handle, yet finite for the parabola algebra.
constexpr float kFar = 1e20f;

// One-dimensional squared distance transform of f (n samples, stride apart) into d.
// v and z are scratch buffers of at least n and n + 1 entries.
void Transform1d(float* f, int n, int stride, std::vector<float>* d, std::vector<int>* v,
                 std::vector<float>* z) {
  auto intersect = [&](int q, int p) {
    return ((f[q * stride] + static_cast<float>(q) * q) -
            (f[p * stride] + static_cast<float>(p) * p)) /
           (2.0f * static_cast<float>(q - p));
  };
  int k = 0;
  (*v)[0] = 0;
  (*z)[0] = -kInf;
  (*z)[1] = kInf;
  for (int q = 1; q < n; ++q) {
    float s = intersect(q, (*v)[k]);
    // z[0] is -inf, so this stops at k == 0 at the latest.
    while (s <= (*z)[k]) {
      --k;
      s = intersect(q, (*v)[k]);
    }
    ++k;
    (*v)[k] = q;
    (*z)[k] = s;
    (*z)[k + 1] = kInf;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while ((*z)[k + 1] < static_cast<float>(q)) ++k;
    const int p = (*v)[k];
    (*d)[q] = static_cast<float>(q - p) * (q - p) + f[p * stride];
  }
  for (int q = 0; q < n; ++q) f[q * stride] = (*d)[q];
}

}  // namespace

Eigen::MatrixXf DistanceTransform(const GridMask& mask) {
  const int sx = static_cast<int>(mask.rows());
  const int sy = static_cast<int>(mask.cols());
  Eigen::MatrixXf out(sx, sy);
  if (sx == 0 || sy == 0) return out;
  bool any = false;
  for (int iy = 0; iy < sy; ++iy) {
    for (int ix = 0; ix < sx; ++ix) {
      const bool set = mask(ix, iy) != 0;
      out(ix, iy) = set ? 0.0f : kFar;
      any = any || set;
    }
  }
  if (!any) {
    out.setConstant(kInf);
    return out;
  }
  const int n = std::max(sx, sy);
  std::vector<float> d(n);
  std::vector<int> v(n);
  std::vector<float> z(n + 1);
  float* data = out.data();
  // Along x (contiguous), then along y (stride sx).
  for (int iy = 0; iy < sy; ++iy)
    Transform1d(data + static_cast<size_t>(iy) * sx, sx, 1, &d, &v, &z);
  for (int ix = 0; ix < sx; ++ix) Transform1d(data + ix, sy, sx, &d, &v, &z);
  for (int i = 0; i < sx * sy; ++i) data[i] = std::sqrt(data[i]);
  return out;
}

}  // namespace cairn::planner
