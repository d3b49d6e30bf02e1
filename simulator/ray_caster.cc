#include "simulator/ray_caster.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <Eigen/Geometry>

namespace cairn::sim {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Half extents and centre offset of a geom's box in its own frame.
bool LocalBox(const mjModel* m, int g, double half[3], double offset[3]) {
  const double* s = m->geom_size + 3 * g;
  offset[0] = offset[1] = offset[2] = 0.0;
  switch (m->geom_type[g]) {
    case mjGEOM_PLANE:
      return false;
    case mjGEOM_SPHERE:
      half[0] = half[1] = half[2] = s[0];
      return true;
    case mjGEOM_CAPSULE:
      half[0] = half[1] = s[0];
      half[2] = s[1] + s[0];
      return true;
    case mjGEOM_CYLINDER:
      half[0] = half[1] = s[0];
      half[2] = s[1];
      return true;
    case mjGEOM_ELLIPSOID:
    case mjGEOM_BOX:
      half[0] = s[0];
      half[1] = s[1];
      half[2] = s[2];
      return true;
    case mjGEOM_HFIELD: {
      const double* h = m->hfield_size + 4 * m->geom_dataid[g];
      half[0] = h[0];
      half[1] = h[1];
      half[2] = 0.5 * (h[2] + h[3]);
      offset[2] = 0.5 * (h[2] - h[3]);
      return true;
    }
    default: {
      // Meshes and anything else: the bounding sphere MuJoCo computed.
      const double r = m->geom_rbound[g];
      half[0] = half[1] = half[2] = r;
      return true;
    }
  }
}

bool GeomVisible(const mjModel* m, int g) {
  const int type = m->geom_type[g];
  if (type == mjGEOM_PLANE || type == mjGEOM_HFIELD) return true;
  if (m->geom_group[g] >= 4) return false;
  const int mat = m->geom_matid[g];
  const float alpha = mat >= 0 ? m->mat_rgba[4 * mat + 3] : m->geom_rgba[4 * g + 3];
  return alpha > 0.f;
}

double Narrow(const mjModel* m, const mjData* d, int g, int type, const double origin[3],
              const double dir[3]) {
  switch (type) {
    case mjGEOM_HFIELD:
      return RayHeightField(m, d, g, origin, dir);
    case mjGEOM_MESH:
      return mj_rayMesh(m, d, g, origin, dir);
    default:
      return mju_rayGeom(d->geom_xpos + 3 * g, d->geom_xmat + 9 * g, m->geom_size + 3 * g, origin,
                         dir, type);
  }
}

// Slab test of a ray against an axis-aligned box [lo, hi]; returns the entry and exit
// parameters (entry clamped at 0) or false when it misses.
bool RaySlab(const double lo[3], const double hi[3], const double p[3], const double v[3],
             double* t_in, double* t_out, int* entry_axis) {
  double t0 = 0.0, t1 = kInfinity;
  *entry_axis = -1;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(v[k]) < 1e-15) {
      if (p[k] < lo[k] || p[k] > hi[k]) return false;
      continue;
    }
    double ta = (lo[k] - p[k]) / v[k];
    double tb = (hi[k] - p[k]) / v[k];
    if (ta > tb) std::swap(ta, tb);
    if (ta > t0) {
      t0 = ta;
      *entry_axis = k;
    }
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  *t_in = t0;
  *t_out = t1;
  return true;
}

// Moller-Trumbore ray-triangle intersection; returns the ray parameter or -1.
double RayTriangle(const double a[3], const double b[3], const double c[3], const double p[3],
                   const double v[3]) {
  const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double q[3] = {v[1] * e2[2] - v[2] * e2[1], v[2] * e2[0] - v[0] * e2[2],
                       v[0] * e2[1] - v[1] * e2[0]};
  const double det = e1[0] * q[0] + e1[1] * q[1] + e1[2] * q[2];
  if (std::abs(det) < 1e-15) return -1.0;
  const double inv = 1.0 / det;
  const double s[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
  const double u = (s[0] * q[0] + s[1] * q[1] + s[2] * q[2]) * inv;
  if (u < -1e-12 || u > 1.0 + 1e-12) return -1.0;
  const double r[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2],
                       s[0] * e1[1] - s[1] * e1[0]};
  const double w = (v[0] * r[0] + v[1] * r[1] + v[2] * r[2]) * inv;
  if (w < -1e-12 || u + w > 1.0 + 1e-12) return -1.0;
  const double t = (e2[0] * r[0] + e2[1] * r[1] + e2[2] * r[2]) * inv;
  return t >= 0.0 ? t : -1.0;
}

// A height field's surface in its own frame: (nrow x ncol) heights over [-sx, sx] x [-sy, sy].
struct HeightSurface {
  int nrow, ncol;
  const float* data;
  double sx, sy, sz;
  double dx, dy;  ///< cell size

  double height(int r, int c) const { return static_cast<double>(data[r * ncol + c]) * sz; }
  // The surface's height along the side wall `axis` (0: x, 1: y) that a ray with direction v
  // enters through at point e.
  double SideWallEdge(int axis, const double e[3], const double v[3]) const {
    if (axis == 0) {
      const int c = v[0] > 0 ? 0 : ncol - 1;
      const double gy = std::clamp((e[1] + sy) / dy, 0.0, nrow - 1.0);
      const int r = std::min(static_cast<int>(gy), nrow - 2);
      return height(r, c) + (height(r + 1, c) - height(r, c)) * (gy - r);
    }
    const int r = v[1] > 0 ? 0 : nrow - 1;
    const double gx = std::clamp((e[0] + sx) / dx, 0.0, ncol - 1.0);
    const int c = std::min(static_cast<int>(gx), ncol - 2);
    return height(r, c) + (height(r, c + 1) - height(r, c)) * (gx - c);
  }
  // The ray's hit on the two triangles of cell (r, c), or -1.
  double CellHit(int r, int c, const double p[3], const double v[3]) const {
    const double x0 = c * dx - sx, x1 = (c + 1) * dx - sx;
    const double y0 = r * dy - sy, y1 = (r + 1) * dy - sy;
    const double a[3] = {x0, y0, height(r, c)}, b[3] = {x1, y1, height(r + 1, c + 1)};
    const double c1[3] = {x1, y0, height(r, c + 1)}, c2[3] = {x0, y1, height(r + 1, c)};
    double hit = RayTriangle(a, b, c1, p, v);
    const double hit2 = RayTriangle(a, b, c2, p, v);
    if (hit2 >= 0.0 && (hit < 0.0 || hit2 < hit)) hit = hit2;
    return hit;
  }
  // The first hit on the surface for ray parameters in [t_in, t_out], or -1: walks the cells
  // under the ray's footprint in order (2-D DDA), skipping those it passes above.
  double Walk(const double p[3], const double v[3], double t_in, double t_out) const;
};

double HeightSurface::Walk(const double p[3], const double v[3], double t_in, double t_out) const {
  const double gx0 = (p[0] + t_in * v[0] + sx) / dx;
  const double gy0 = (p[1] + t_in * v[1] + sy) / dy;
  int c = std::clamp(static_cast<int>(std::floor(gx0)), 0, ncol - 2);
  int r = std::clamp(static_cast<int>(std::floor(gy0)), 0, nrow - 2);
  const int step_c = v[0] > 0 ? 1 : -1;
  const int step_r = v[1] > 0 ? 1 : -1;
  const double inf = kInfinity;
  const double delta_c = std::abs(v[0]) > 1e-15 ? dx / std::abs(v[0]) : inf;
  const double delta_r = std::abs(v[1]) > 1e-15 ? dy / std::abs(v[1]) : inf;
  // Ray parameter at which the footprint crosses the next cell boundary in x and in y.
  double next_c = inf, next_r = inf;
  if (delta_c < inf) next_c = ((v[0] > 0 ? c + 1 : c) * dx - sx - p[0]) / v[0];
  if (delta_r < inf) next_r = ((v[1] > 0 ? r + 1 : r) * dy - sy - p[1]) / v[1];
  double t_cell = t_in;
  while (true) {
    const double t_exit = std::min({next_c, next_r, t_out});
    // Skip the cell when the ray stays above its highest corner.
    const double z_low = std::min(p[2] + t_cell * v[2], p[2] + t_exit * v[2]);
    const double top = std::max(std::max(height(r, c), height(r, c + 1)),
                                std::max(height(r + 1, c), height(r + 1, c + 1)));
    if (z_low <= top + 1e-9) {
      const double hit = CellHit(r, c, p, v);
      if (hit >= 0.0) return hit;
    }
    if (t_exit >= t_out) return -1.0;
    if (next_c <= next_r) {
      c += step_c;
      t_cell = next_c;
      next_c += delta_c;
    } else {
      r += step_r;
      t_cell = next_r;
      next_r += delta_r;
    }
    if (c < 0 || c > ncol - 2 || r < 0 || r > nrow - 2) return -1.0;
  }
}

}  // namespace

double RayHeightField(const mjModel* m, const mjData* d, int g, const double pnt[3],
                      const double vec[3]) {
  const int h = m->geom_dataid[g];
  const double* size = m->hfield_size + 4 * h;
  HeightSurface surface;
  surface.nrow = m->hfield_nrow[h];
  surface.ncol = m->hfield_ncol[h];
  surface.data = m->hfield_data + m->hfield_adr[h];
  surface.sx = size[0];
  surface.sy = size[1];
  surface.sz = size[2];
  surface.dx = 2.0 * size[0] / (surface.ncol - 1);
  surface.dy = 2.0 * size[1] / (surface.nrow - 1);
  const double base = size[3];
  const double sx = size[0], sy = size[1], sz = size[2];

  // The ray in the height field's frame (geom_xmat is row-major, local = R^T (p - pos)).
  const double* pos = d->geom_xpos + 3 * g;
  const double* mat = d->geom_xmat + 9 * g;
  const double dif[3] = {pnt[0] - pos[0], pnt[1] - pos[1], pnt[2] - pos[2]};
  double p[3], v[3];
  for (int i = 0; i < 3; ++i) {
    p[i] = mat[i] * dif[0] + mat[3 + i] * dif[1] + mat[6 + i] * dif[2];
    v[i] = mat[i] * vec[0] + mat[3 + i] * vec[1] + mat[6 + i] * vec[2];
  }

  // The base box under the surface.
  double best = -1.0;
  double t_in = 0.0, t_out = 0.0;
  int axis = -1;
  {
    const double lo[3] = {-sx, -sy, -base}, hi[3] = {sx, sy, 0.0};
    // From inside the base a ray meets its far side (as mj_rayHfield reports).
    if (RaySlab(lo, hi, p, v, &t_in, &t_out, &axis)) best = axis < 0 ? t_out : t_in;
  }
  // The box holding the surface; nothing more to find if the ray misses it.
  const double lo[3] = {-sx, -sy, 0.0}, hi[3] = {sx, sy, sz};
  if (!RaySlab(lo, hi, p, v, &t_in, &t_out, &axis)) return best;
  if (best >= 0.0) t_out = std::min(t_out, best);
  if (t_in > t_out) return best;

  // Entering through a side wall below the surface edge: the side of the prism is hit.
  if (t_in > 0.0 && (axis == 0 || axis == 1)) {
    const double e[3] = {p[0] + t_in * v[0], p[1] + t_in * v[1], p[2] + t_in * v[2]};
    if (e[2] <= surface.SideWallEdge(axis, e, v)) return best >= 0.0 ? std::min(best, t_in) : t_in;
  }
  const double hit = surface.Walk(p, v, t_in, t_out);
  if (hit < 0.0) return best;
  return best >= 0.0 ? std::min(best, hit) : hit;
}

namespace {

// A geom that a group's rays may hit, relative to the sensor.
struct Candidate {
  double min_distance;  ///< from the sensor to the box (plane: along its normal)
  double lo[3];         ///< box corners minus the sensor position; plane: its unit normal
  double hi[3];         ///< plane: hi[0] = the sensor's signed distance from it
  int geom;
  int type;
  bool infinite;  ///< a plane
  bool exact;     ///< an axis-aligned box: the slab test is the exact intersection
  bool inside;    ///< the sensor is inside the box
  /// A plane, or a box turned against the world's axes: its index in GroupCandidates::oriented
  /// (its own frame, for an exact test there), or -1.
  int oriented;
};

// A turned box or a plane in its own frame: the sensor's position there, and its half extents
// (a plane's: the half size of its rendered rectangle, 0 for unbounded).
struct OrientedBox {
  double axes[9];    ///< geom_xmat: box frame to world, row-major
  double origin[3];  ///< the sensor in the box frame
  double half[3];
};

// The geoms a group's rays may hit: boxes sorted by distance, with their vertical extent
// (beyond which a ray cannot hit any of them), and the planes, tested for every ray.
struct GroupCandidates {
  std::vector<Candidate> boxes;
  /// Per geom id: its index in `boxes`, or -1 (the neighbouring ray's geom is found at once).
  std::vector<int> box_of_geom;
  std::vector<Candidate> planes;
  std::vector<OrientedBox> oriented;
  double z_low{kInfinity};
  double z_high{-kInfinity};
};

// A plane: its distance along its normal bounds every hit from below.
Candidate PlaneCandidate(const mjData* data, const RayScene::Bound& b, const double o[3]) {
  const double* p = data->geom_xpos + 3 * b.geom;
  const double* r = data->geom_xmat + 9 * b.geom;
  Candidate c;
  c.min_distance = std::abs((o[0] - p[0]) * r[2] + (o[1] - p[1]) * r[5] + (o[2] - p[2]) * r[8]);
  c.lo[0] = r[2];
  c.lo[1] = r[5];
  c.lo[2] = r[8];
  c.hi[0] = (o[0] - p[0]) * r[2] + (o[1] - p[1]) * r[5] + (o[2] - p[2]) * r[8];
  c.geom = b.geom;
  c.type = b.type;
  c.infinite = true;
  c.exact = false;
  c.inside = false;
  c.oriented = -1;
  return c;
}

// True when even the box corner deepest on one plane's inner side is outside it.
bool OutsidePyramid(const RayScene::Bound& b, const Eigen::Vector3d planes_world[4],
                    const double o[3]) {
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d& n = planes_world[k];
    double s = 0.0;
    for (int i = 0; i < 3; ++i) s += n[i] * ((n[i] > 0.0 ? b.lo[i] : b.hi[i]) - o[i]);
    if (s > 1e-12) return true;
  }
  return false;
}

// A box, relative to the sensor, `min_d` away from it.
Candidate BoxCandidate(const RayScene::Bound& b, const double o[3], double min_d) {
  Candidate c;
  c.min_distance = min_d;
  c.inside = true;
  for (int k = 0; k < 3; ++k) {
    c.lo[k] = b.lo[k] - o[k];
    c.hi[k] = b.hi[k] - o[k];
    c.inside = c.inside && c.lo[k] <= 0.0 && c.hi[k] >= 0.0;
  }
  c.geom = b.geom;
  c.type = b.type;
  c.infinite = false;
  c.exact = b.exact;
  c.oriented = -1;
  return c;
}

// A turned box or a plane: the sensor's position in its frame, as MuJoCo's ray_map computes it.
OrientedBox MakeOrientedBox(const mjModel* m, const mjData* d, int g, const double o[3]) {
  OrientedBox box;
  const double* pos = d->geom_xpos + 3 * g;
  const double* mat = d->geom_xmat + 9 * g;
  const double dif[3] = {o[0] - pos[0], o[1] - pos[1], o[2] - pos[2]};
  for (int i = 0; i < 9; ++i) box.axes[i] = mat[i];
  for (int k = 0; k < 3; ++k) {
    box.origin[k] = mat[k] * dif[0] + mat[3 + k] * dif[1] + mat[6 + k] * dif[2];
    box.half[k] = m->geom_size[3 * g + k];
  }
  return box;
}

// Broad phase for a whole group: the planes, and the geoms whose box lies within range and
// meets the pyramid holding the group's rays; sorted by distance.
void CollectCandidates(const RayScene& scene, const mjData* data, const double o[3],
                       const Eigen::Matrix3d& rotation, const RayPattern::Group& g,
                       double max_range_m, int exclude_owner, GroupCandidates* out) {
  Eigen::Vector3d planes_world[4];
  if (g.bounded) {
    for (int k = 0; k < 4; ++k) planes_world[k] = rotation * g.planes[k];
  }
  std::vector<Candidate>& all = out->boxes;
  for (const Candidate& c : all) out->box_of_geom[c.geom] = -1;
  all.clear();
  out->oriented.clear();
  const size_t ngeom = static_cast<size_t>(scene.model()->ngeom);
  if (out->box_of_geom.size() < ngeom) out->box_of_geom.resize(ngeom, -1);
  for (const RayScene::Bound& b : scene.bounds()) {
    if (b.owner >= 0 && b.owner == exclude_owner) continue;
    if (b.infinite) {
      all.push_back(PlaneCandidate(data, b, o));
      all.back().oriented = static_cast<int>(out->oriented.size());
      out->oriented.push_back(MakeOrientedBox(scene.model(), data, b.geom, o));
      continue;
    }
    double min_d2 = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double q = std::max(b.lo[i] - o[i], std::max(0.0, o[i] - b.hi[i]));
      min_d2 += q * q;
    }
    const double min_d = std::sqrt(min_d2);
    if (min_d > max_range_m) continue;
    if (g.bounded && OutsidePyramid(b, planes_world, o)) continue;
    all.push_back(BoxCandidate(b, o, min_d));
    if (b.type == mjGEOM_BOX && !b.exact) {
      all.back().oriented = static_cast<int>(out->oriented.size());
      out->oriented.push_back(MakeOrientedBox(scene.model(), data, b.geom, o));
    }
  }
  std::sort(all.begin(), all.end(),
            [](const Candidate& a, const Candidate& b) { return a.min_distance < b.min_distance; });
  // Planes are unbounded: keep them aside. The rest are boxes; their vertical extent bounds
  // where a ray can still hit anything.
  out->planes.clear();
  out->z_low = kInfinity;
  out->z_high = -kInfinity;
  size_t kept = 0;
  for (const Candidate& c : all) {
    if (c.infinite) {
      out->planes.push_back(c);
      continue;
    }
    out->z_low = std::min(out->z_low, c.lo[2]);
    out->z_high = std::max(out->z_high, c.hi[2]);
    out->box_of_geom[c.geom] = static_cast<int>(kept);
    all[kept++] = c;
  }
  all.resize(kept);
}

// Narrow phase, L neighbouring rays at once on L lanes of doubles (GCC/Clang vector
// extensions): four with AVX2 where the processor has it, two (SSE2, NEON) otherwise; a vector
// wider than the hardware's is split element by element and runs three times slower. For each
// ray: the geom its neighbour hit first (it tightens the search at once), then the planes, then
// the boxes nearest first until the next one lies beyond every lane's nearest hit and beyond
// where the rays leave the boxes' vertical extent. Axis-aligned and turned boxes are tested here
// (slab tests, in the box's own frame for a turned one); other shapes go to MuJoCo's functions
// lane by lane. The rays of a packet are neighbours in the pattern, so they meet nearly the same
// candidates; a lane's result is its ray's alone (the tests compare every ray with mj_ray).
template <int L>
struct Lanes;
template <>
struct Lanes<2> {
  typedef double V __attribute__((vector_size(16)));
  typedef long long M __attribute__((vector_size(16)));
};
template <>
struct Lanes<4> {
  typedef double V __attribute__((vector_size(32)));
  typedef long long M __attribute__((vector_size(32)));
};
constexpr int kMaxLanes = 4;

// 1 / x lane by lane, and +-1e12 for a component within 1e-12 of zero (a slab the ray runs
// along). Vectors by reference: passed by value, a 32-byte vector changes the ABI without AVX.
template <typename V, typename M>
__attribute__((always_inline)) inline void SafeInverse(const V& x, V* inverse) {
  const V zero = {};
  const V one = zero + 1.0;
  const M big = (x < zero ? -x : x) > 1e-12;
  const V q = one / (V)(((M)x & big) | ((M)one & ~big));
  const M pos = x >= zero;
  const V tiny = (V)(((M)(zero + 1e12) & pos) | ((M)(zero - 1e12) & ~pos));
  *inverse = (V)(((M)q & big) | ((M)tiny & ~big));
}

// `rays` rays (1 to L; lanes past them hold the next directions, cast and not written) with
// their direction components at components[0..2]; `warm`: the geoms their neighbours hit (-1).
// Inlined into CastPacket2 and CastPacket4, each compiled for its target.
template <int L>
__attribute__((always_inline)) inline void CastPacket(const mjModel* m, const mjData* data,
                                                      const GroupCandidates& candidates,
                                                      const double o[3], const double rot[9],
                                                      const double* const components[3], int rays,
                                                      const int* warm, double max_range_m,
                                                      RayHit* out) {
  using V = typename Lanes<L>::V;
  using M = typename Lanes<L>::M;
  // World directions, as Eigen's rotation * direction computes them (same order of operations).
  // Lanes past `rays` hold the next rays of the pattern: cast, never written.
  V d[3];
  for (int k = 0; k < 3; ++k) std::memcpy(&d[k], components[k], sizeof(V));
  V v[3], inv[3];
  const V zero = {};
  for (int k = 0; k < 3; ++k) {
    v[k] = (rot[k] * d[0] + rot[k + 3] * d[1]) + rot[k + 6] * d[2];
    SafeInverse<V, M>(v[k], &inv[k]);
  }
  // Beyond `reach` a ray has left the boxes' vertical extent.
  V reach = zero + max_range_m;
  for (int j = 0; j < L; ++j) {
    if (v[2][j] > 1e-12) {
      reach[j] = std::max(0.0, candidates.z_high * inv[2][j]);
    } else if (v[2][j] < -1e-12) {
      reach[j] = std::max(0.0, candidates.z_low * inv[2][j]);
    }
  }
  V best = zero + max_range_m;
  int best_geom[L];
  for (int j = 0; j < L; ++j) best_geom[j] = -1;

  auto lane_dir = [&](int j, double w[3]) __attribute__((always_inline)) {
    w[0] = v[0][j];
    w[1] = v[1][j];
    w[2] = v[2][j];
  };
  // The lanes in `nearer` hit geom `geom` at x.
  auto take = [&](const M& nearer, const V& x, int geom) __attribute__((always_inline)) {
    best = (V)(((M)x & nearer) | ((M)best & ~nearer));
    for (int j = 0; j < L; ++j) {
      if (nearer[j]) best_geom[j] = geom;
    }
  };
  auto keep = [&](int j, double x, int geom) __attribute__((always_inline)) {
    if (x >= 0.0 && x <= best[j]) {
      best[j] = x;
      best_geom[j] = geom;
    }
  };
  // Inlined (a call would leave the vector code on the default target, and pass vectors by value).
  auto test = [&](const Candidate& c) __attribute__((always_inline)) {
    if (c.infinite) {
      // MuJoCo's plane rule (mj_ray's), on the lanes: the front face only, within the
      // rendered rectangle when the plane has a size.
      const OrientedBox& plane = candidates.oriented[c.oriented];
      const V vz = (c.lo[0] * v[0] + c.lo[1] * v[1]) + c.lo[2] * v[2];
      M front = (vz <= -mjMINVAL) & (-c.hi[0] >= best * vz);
      long long any = 0;
      for (int j = 0; j < L; ++j) any |= front[j];
      if (any == 0) return;
      const V x = -plane.origin[2] / (V)(((M)vz & front) | ((M)(zero - 1.0) & ~front));
      front &= x >= zero;
      for (int axis = 0; axis < 2; ++axis) {
        if (!(plane.half[axis] > 0.0)) continue;
        const double* r = plane.axes;
        const V va = (r[axis] * v[0] + r[3 + axis] * v[1]) + r[6 + axis] * v[2];
        const V e = plane.origin[axis] + x * va;
        const V ae = e < zero ? -e : e;
        front &= ae <= plane.half[axis];
      }
      const M nearer = front & (x <= best);
      take(nearer, x, c.geom);
      return;
    }
    V t_in = zero, t_out = best, far = zero + kInfinity;
    for (int k = 0; k < 3; ++k) {
      const V a = c.lo[k] * inv[k];
      const V b = c.hi[k] * inv[k];
      const M a_near = a < b;
      const V t_near = (V)(((M)a & a_near) | ((M)b & ~a_near));
      const V t_far = (V)(((M)b & a_near) | ((M)a & ~a_near));
      t_in = t_near > t_in ? t_near : t_in;
      t_out = t_far < t_out ? t_far : t_out;
      far = t_far < far ? t_far : far;
    }
    const M hit = t_in <= t_out;
    long long any = 0;
    for (int j = 0; j < L; ++j) any |= hit[j];
    if (any == 0) return;
    if (c.oriented >= 0) {
      // The same slab test in the box's own frame: exact for a turned box, as mju_rayGeom's
      // face tests are; from inside, the far side.
      const OrientedBox& box = candidates.oriented[c.oriented];
      V enter = zero - kInfinity, exit = zero + kInfinity;
      for (int k = 0; k < 3; ++k) {
        const V lv = (box.axes[k] * v[0] + box.axes[3 + k] * v[1]) + box.axes[6 + k] * v[2];
        V il;
        SafeInverse<V, M>(lv, &il);
        const V ta = (-box.half[k] - box.origin[k]) * il;
        const V tb = (box.half[k] - box.origin[k]) * il;
        const M a_near = ta < tb;
        const V t_near = (V)(((M)ta & a_near) | ((M)tb & ~a_near));
        const V t_far = (V)(((M)tb & a_near) | ((M)ta & ~a_near));
        enter = t_near > enter ? t_near : enter;
        exit = t_far < exit ? t_far : exit;
      }
      const M outside = enter >= zero;
      const V x = (V)(((M)enter & outside) | ((M)exit & ~outside));
      const M nearer = hit & (enter <= exit) & (x >= zero) & (x <= best);
      take(nearer, x, c.geom);
      return;
    }
    if (c.exact) {
      // From outside: the entry; from inside a box a ray meets its far side.
      const V x = c.inside ? far : t_in;
      const M nearer = hit & (x >= zero) & (x <= best);
      take(nearer, x, c.geom);
      return;
    }
    for (int j = 0; j < L; ++j) {
      if (!hit[j]) continue;
      double w[3];
      lane_dir(j, w);
      keep(j, Narrow(m, data, c.geom, c.type, o, w), c.geom);
    }
  };

  const Candidate* const boxes = candidates.boxes.data();
  const Candidate* const boxes_end = boxes + candidates.boxes.size();
  int tested[L];
  int n_tested = 0;
  for (int j = 0; j < L; ++j) {
    if (warm[j] < 0) continue;
    const int k = candidates.box_of_geom[warm[j]];
    if (k < 0) continue;
    bool seen = false;
    for (int t = 0; t < n_tested; ++t) seen = seen || tested[t] == warm[j];
    if (seen) continue;
    tested[n_tested++] = warm[j];
    test(boxes[k]);
  }
  for (const Candidate& c : candidates.planes) test(c);
  auto bound = [&]() __attribute__((always_inline)) {
    const V lim = best < reach ? best : reach;
    double most = lim[0];
    for (int j = 1; j < L; ++j) most = std::max(most, lim[j]);
    return most;
  };
  double limit = bound();
  for (const Candidate* c = boxes; c != boxes_end; ++c) {
    if (c->min_distance > limit) break;
    bool seen = false;
    for (int t = 0; t < n_tested; ++t) seen = seen || tested[t] == c->geom;
    if (seen) continue;
    test(*c);
    limit = bound();
  }
  for (int j = 0; j < rays; ++j) {
    out[j] = RayHit{best_geom[j] >= 0 ? best[j] : -1.0, best_geom[j]};
  }
}

// One packet, compiled for each lane count's target and called per packet (inlined into the
// group's loop, the packet's code was a fifth slower).
__attribute__((noinline)) void CastPacket2(const mjModel* m, const mjData* data,
                                           const GroupCandidates& candidates, const double o[3],
                                           const double rot[9], const double* const components[3],
                                           int rays, const int* warm, double max_range_m,
                                           RayHit* out) {
  CastPacket<2>(m, data, candidates, o, rot, components, rays, warm, max_range_m, out);
}

// Four lanes need AVX2 (x86-64 only). Sanitizer builds take the default path only; the plain
// build tests the AVX2 one where the processor has it.
#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define CAIRN_SANITIZED_BUILD 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define CAIRN_SANITIZED_BUILD 1
#endif
#if defined(__x86_64__) && !defined(CAIRN_SANITIZED_BUILD)
#define CAIRN_PACKETS_AVX2 1
__attribute__((target("avx2"), noinline)) void CastPacket4(const mjModel* m, const mjData* data,
                                                           const GroupCandidates& candidates,
                                                           const double o[3], const double rot[9],
                                                           const double* const components[3],
                                                           int rays, const int* warm,
                                                           double max_range_m, RayHit* out) {
  CastPacket<4>(m, data, candidates, o, rot, components, rays, warm, max_range_m, out);
}

bool HasAvx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}
#endif

using PacketFunction = void (*)(const mjModel*, const mjData*, const GroupCandidates&,
                                const double*, const double*, const double* const*, int, const int*,
                                double, RayHit*);

// A group's rays, L at a time.
template <int L, PacketFunction Packet>
void CastPackets(const mjModel* m, const mjData* data, const GroupCandidates& candidates,
                 const double o[3], const Eigen::Matrix3d& rotation, const RayPattern& pattern,
                 const RayPattern::Group& g, double max_range_m, RayHit* hits, int hits_base) {
  const size_t n = pattern.directions.size();
  const bool packed = pattern.components.size() == 3 * (n + kMaxLanes);
  const double* const column[3] = {pattern.components.data(),
                                   pattern.components.data() + n + kMaxLanes,
                                   pattern.components.data() + 2 * (n + kMaxLanes)};
  double gathered[3][L];
  // Column-major, as Eigen stores it.
  double rot[9];
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) rot[3 * c + r] = rotation(r, c);
  }
  for (int i = g.begin; i < g.end; i += L) {
    const int rays = std::min(L, g.end - i);
    // The geom each ray's neighbour hit (usually the same, and it tightens the search): the
    // neighbour one stride back, or the packet's first ray's neighbour when that one is in this
    // packet and not cast yet.
    int warm[L];
    for (int j = 0; j < L; ++j) {
      int source = i + j - pattern.warm_stride;
      if (source >= i) source = i - 1;
      warm[j] = j < rays && source >= g.begin ? hits[source - hits_base].geom : -1;
    }
    const double* components[3];
    if (packed) {
      for (int k = 0; k < 3; ++k) components[k] = column[k] + i;
    } else {
      for (int k = 0; k < 3; ++k) {
        for (int j = 0; j < L; ++j) {
          gathered[k][j] = pattern.directions[i + std::min(j, rays - 1)][k];
        }
        components[k] = gathered[k];
      }
    }
    Packet(m, data, candidates, o, rot, components, rays, warm, max_range_m,
           hits + (i - hits_base));
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// RayScene

RayScene::RayScene(const mjModel* model)
    : model_(model), visible_(model->ngeom, 0), owner_(model->ngeom, -1) {
  for (int g = 0; g < model->ngeom; ++g) visible_[g] = GeomVisible(model, g) ? 1 : 0;
}

void RayScene::SetOwner(int geom, int owner) { owner_.at(geom) = owner; }

void RayScene::SetVisible(int geom, bool visible) { visible_.at(geom) = visible ? 1 : 0; }

void RayScene::Update(const mjData* d) {
  const mjModel* m = model_;
  bounds_.clear();
  for (int g = 0; g < m->ngeom; ++g) {
    if (!visible_[g]) continue;
    Bound b;
    b.geom = g;
    b.type = m->geom_type[g];
    b.owner = owner_[g];
    double half[3], offset[3];
    if (!LocalBox(m, g, half, offset)) {
      b.infinite = true;
      bounds_.push_back(b);
      continue;
    }
    // World box of the rotated local box: centre R*offset, half extents |R| * half.
    const double* p = d->geom_xpos + 3 * g;
    const double* r = d->geom_xmat + 9 * g;
    double radius2 = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double c =
          p[i] + r[3 * i] * offset[0] + r[3 * i + 1] * offset[1] + r[3 * i + 2] * offset[2];
      const double e = std::abs(r[3 * i]) * half[0] + std::abs(r[3 * i + 1]) * half[1] +
                       std::abs(r[3 * i + 2]) * half[2];
      b.center[i] = c;
      b.lo[i] = c - e;
      b.hi[i] = c + e;
      radius2 += e * e;
    }
    b.radius = std::sqrt(radius2);
    if (b.type != mjGEOM_HFIELD) b.radius = std::min(b.radius, m->geom_rbound[g]);
    // A box whose axes are the world's (walls, floors, platforms) equals its bounding box, so
    // the slab test gives the exact hit distance.
    if (b.type == mjGEOM_BOX) {
      int unit = 0;
      for (int i = 0; i < 9; ++i) {
        const double a = std::abs(r[i]);
        if (a > 1.0 - 1e-12) {
          ++unit;
        } else if (a > 1e-12) {
          unit = -100;
        }
      }
      b.exact = unit == 3;
    }
    bounds_.push_back(b);
  }
}

// ---------------------------------------------------------------------------------------------
// RayPattern

void RayPattern::BuildGroups(int group_size) {
  groups.clear();
  group_size = std::max(1, group_size);
  const int n = static_cast<int>(directions.size());
  BuildComponents();
  for (int begin = 0; begin < n; begin += group_size) {
    Group g;
    g.begin = begin;
    g.end = std::min(n, begin + group_size);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int i = g.begin; i < g.end; ++i) sum += directions[i];
    g.axis = sum.norm() > 1e-9 ? sum.normalized() : directions[g.begin];
    // A frame around the axis, and the angular extent of the rays towards its two sides.
    const Eigen::Vector3d a = g.axis;
    const Eigen::Vector3d u = a.unitOrthogonal();
    const Eigen::Vector3d w = a.cross(u);
    double u_min = 0.0, u_max = 0.0, w_min = 0.0, w_max = 0.0;
    bool ok = true;
    for (int i = g.begin; i < g.end; ++i) {
      const Eigen::Vector3d& d = directions[i];
      const double along = d.dot(a);
      if (along <= 1e-6) {
        ok = false;  // wider than a half space: no pyramid
        break;
      }
      const double au = std::atan2(d.dot(u), along), aw = std::atan2(d.dot(w), along);
      u_min = std::min(u_min, au);
      u_max = std::max(u_max, au);
      w_min = std::min(w_min, aw);
      w_max = std::max(w_max, aw);
    }
    // A small margin keeps rounding from dropping a geom that a boundary ray grazes.
    constexpr double kMargin = 1e-6;
    constexpr double kLimit = 1.5;  // about 86 deg: beyond it a side plane means little
    if (ok && u_max < kLimit && -u_min < kLimit && w_max < kLimit && -w_min < kLimit) {
      u_min -= kMargin;
      u_max += kMargin;
      w_min -= kMargin;
      w_max += kMargin;
      // A direction at angle t towards u satisfies d . (-a sin T + u cos T) <= 0 iff t <= T
      // (whatever its w component), and the mirror for the lower bound; same towards w.
      g.planes[0] = -a * std::sin(u_max) + u * std::cos(u_max);
      g.planes[1] = a * std::sin(u_min) - u * std::cos(u_min);
      g.planes[2] = -a * std::sin(w_max) + w * std::cos(w_max);
      g.planes[3] = a * std::sin(w_min) - w * std::cos(w_min);
      g.bounded = true;
    }
    groups.push_back(g);
  }
}

void RayPattern::BuildComponents() {
  const size_t n = directions.size();
  components.assign(3 * (n + kMaxLanes), 0.0);
  for (size_t k = 0; k < 3; ++k) {
    double* column = components.data() + k * (n + kMaxLanes);
    for (size_t i = 0; i < n + kMaxLanes; ++i)
      column[i] = n > 0 ? directions[std::min(i, n - 1)][k] : 0.0;
  }
}

// ---------------------------------------------------------------------------------------------
// RayCaster

RayCaster::RayCaster(ThreadPool* pool, int lanes)
    : pool_(pool), lanes_(lanes == 2 ? 2 : MostLanes()) {}

int RayCaster::MostLanes() {
#if defined(CAIRN_PACKETS_AVX2)
  return HasAvx2() ? 4 : 2;
#else
  return 2;
#endif
}

void RayCaster::Cast(const RayScene& scene, const mjData* data, const Eigen::Vector3d& origin,
                     const Eigen::Matrix3d& rotation, const RayPattern& pattern, int group_begin,
                     int group_end, double max_range_m, int exclude_owner, RayHit* hits,
                     int hits_base) const {
  group_begin = std::max(0, group_begin);
  group_end = std::min(group_end, static_cast<int>(pattern.groups.size()));
  const int count = group_end - group_begin;
  if (count <= 0) return;
  auto task = [&](int i) {
    CastGroup(scene, data, origin, rotation, pattern, group_begin + i, max_range_m, exclude_owner,
              hits, hits_base);
  };
  if (pool_ != nullptr) {
    pool_->ParallelFor(count, task);
  } else {
    for (int i = 0; i < count; ++i) task(i);
  }
}

void RayCaster::CastGroup(const RayScene& scene, const mjData* data, const Eigen::Vector3d& origin,
                          const Eigen::Matrix3d& rotation, const RayPattern& pattern, int group,
                          double max_range_m, int exclude_owner, RayHit* hits,
                          int hits_base) const {
  const RayPattern::Group& g = pattern.groups[group];
  const double o[3] = {origin.x(), origin.y(), origin.z()};
  thread_local GroupCandidates candidates;
  CollectCandidates(scene, data, o, rotation, g, max_range_m, exclude_owner, &candidates);
#if defined(CAIRN_PACKETS_AVX2)
  if (lanes_ == 4) {
    CastPackets<4, CastPacket4>(scene.model(), data, candidates, o, rotation, pattern, g,
                                max_range_m, hits, hits_base);
    return;
  }
#endif
  CastPackets<2, CastPacket2>(scene.model(), data, candidates, o, rotation, pattern, g, max_range_m,
                              hits, hits_base);
}

void RayCaster::CastWithMjRay(const mjModel* model, const mjData* data,
                              const Eigen::Vector3d& origin, const Eigen::Matrix3d& rotation,
                              const RayPattern& pattern, int group_begin, int group_end,
                              double max_range_m, RayHit* hits, int hits_base) {
  static const mjtByte kGroups[mjNGROUP] = {1, 1, 1, 0, 0, 0};
  const double o[3] = {origin.x(), origin.y(), origin.z()};
  group_end = std::min(group_end, static_cast<int>(pattern.groups.size()));
  for (int gi = std::max(0, group_begin); gi < group_end; ++gi) {
    const RayPattern::Group& g = pattern.groups[gi];
    for (int i = g.begin; i < g.end; ++i) {
      const Eigen::Vector3d dw = rotation * pattern.directions[i];
      const double v[3] = {dw.x(), dw.y(), dw.z()};
      int geom = -1;
      const double x = mj_ray(model, data, o, v, kGroups, 1, -1, &geom);
      if (x >= 0.0 && x <= max_range_m) {
        hits[i - hits_base] = {x, geom};
      } else {
        hits[i - hits_base] = {-1.0, -1};
      }
    }
  }
}

}  // namespace cairn::sim
