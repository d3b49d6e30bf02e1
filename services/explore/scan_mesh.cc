#include "services/explore/scan_mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "services/explore/field_checks.h"
#include <Eigen/Geometry>

namespace cairn::explore {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

using internal::Fail;
using internal::Require;

bool FinitePositive(double v) { return std::isfinite(v) && v > 0.0; }

int Finite(const Eigen::Vector3f& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
}

// Quad corners in (line, beam) offsets: 0 = (0, 0), 1 = (1, 0), 2 = (1, 1), 3 = (0, 1).
constexpr std::array<int, 4> kCornerLine{0, 1, 1, 0};
constexpr std::array<int, 4> kCornerBeam{0, 0, 1, 1};

// The triangles of a quad by its mask of corners with a return (bit c = corner c), as corner
// triples, counter-clockwise in (line, beam); -1 ends the list. Four corners: split along the
// fixed diagonal 0-2. Three: the triangle of those three. Fewer: none.
struct QuadTriangles {
  int count;
  std::array<std::array<int, 3>, 2> corners;
};
constexpr std::array<QuadTriangles, 16> kQuadTriangles{{
    {0, {}},                        // 0000
    {0, {}},                        // 0001
    {0, {}},                        // 0010
    {0, {}},                        // 0011
    {0, {}},                        // 0100
    {0, {}},                        // 0101
    {0, {}},                        // 0110
    {1, {{{0, 1, 2}, {0, 0, 0}}}},  // 0111: corners 0, 1, 2
    {0, {}},                        // 1000
    {0, {}},                        // 1001
    {0, {}},                        // 1010
    {1, {{{0, 1, 3}, {0, 0, 0}}}},  // 1011: corners 0, 1, 3
    {0, {}},                        // 1100
    {1, {{{0, 2, 3}, {0, 0, 0}}}},  // 1101: corners 0, 2, 3
    {1, {{{1, 2, 3}, {0, 0, 0}}}},  // 1110: corners 1, 2, 3
    {2, {{{0, 1, 2}, {0, 2, 3}}}},  // 1111
}};

// Bit of the neighbour at offset (dl, db) != (0, 0) in a point's 8-neighbour mask; increasing
// bits are increasing index offsets dl * beams_per_line + db.
constexpr int NeighbourBit(int dl, int db) {
  const int k = (dl + 1) * 3 + (db + 1);
  return k > 4 ? k - 1 : k;
}
constexpr std::array<int, 8> kBitLine{-1, -1, -1, 0, 0, 1, 1, 1};
constexpr std::array<int, 8> kBitBeam{-1, 0, 1, -1, 1, -1, 0, 1};

// Neighbour bits that corner `v` of the corner triple `c` gets from the triangle's other two.
constexpr int TriangleBits(const std::array<int, 3>& c, int v) {
  int bits = 0;
  for (int w = 0; w < 3; ++w) {
    if (w == v) continue;
    bits |= 1 << NeighbourBit(kCornerLine[c[w]] - kCornerLine[c[v]],
                              kCornerBeam[c[w]] - kCornerBeam[c[v]]);
  }
  return bits;
}

// Per point accumulators and the rejection bounds, shared by the triangle paths below.
struct Accumulator {
  ScanMesh* mesh;
  float* par;
  Eigen::Vector3f* nsum;
  int32_t* nmask;
  Eigen::Vector3f origin;
  float side_ratio2;
  float edge_k2;

  // The law-of-sines and spacing tests on a triangle's squared sides, |cross|² (4 A²) and its
  // smallest squared range.
  bool Reject(float l1, float l2, float l3, float cross2, float rmin2) const {
    const float lmax = std::max(l1, std::max(l2, l3));
    const float lmin = std::min(l1, std::min(l2, l3));
    return !(cross2 > 1e-12f * lmax * lmax) ||  // degenerate (collinear)
           lmax > side_ratio2 * lmin ||         // law of sines
           (edge_k2 > 0.f && lmax > edge_k2 * rmin2);
  }

  // Records triangle (a, b, c) with cross = (b - a) x (c - a) as accepted or rejected.
  void Add(bool reject, int a, int b, int c, const Eigen::Vector3f& centroid3,
           Eigen::Vector3f cross, float cross2, int bits_a, int bits_b, int bits_c) {
    const Eigen::Vector3i tri(a, b, c);
    if (reject) {
      mesh->rejected_triangles.push_back(tri);
      return;
    }
    mesh->triangles.push_back(tri);
    if (cross.dot(3.f * origin - centroid3) < 0.f) cross = -cross;  // towards the sensor
    const float third_area = std::sqrt(cross2) * (0.5f / 3.f);
    par[a] += third_area;
    par[b] += third_area;
    par[c] += third_area;
    nsum[a] += cross;
    nsum[b] += cross;
    nsum[c] += cross;
    nmask[a] |= bits_a;
    nmask[b] |= bits_b;
    nmask[c] |= bits_c;
  }
};

// Bits of the two triangles of a full quad, (0, 1, 2) and (0, 2, 3).
constexpr int kA0 = TriangleBits({0, 1, 2}, 0), kA1 = TriangleBits({0, 1, 2}, 1),
              kA2 = TriangleBits({0, 1, 2}, 2);
constexpr int kB0 = TriangleBits({0, 2, 3}, 0), kB2 = TriangleBits({0, 2, 3}, 1),
              kB3 = TriangleBits({0, 2, 3}, 2);

}  // namespace

void OrderedScan::Validate() const {
  Require(num_lines >= 0, "OrderedScan.num_lines", "must be >= 0", num_lines);
  Require(beams_per_line >= 0, "OrderedScan.beams_per_line", "must be >= 0", beams_per_line);
  const int64_t cells = static_cast<int64_t>(num_lines) * beams_per_line;
  Require(cells <= std::numeric_limits<int32_t>::max(), "OrderedScan.num_lines",
          "* beams_per_line must fit in int32", cells);
  if (static_cast<int64_t>(points_m.size()) != cells) {
    const std::string rule =
        "must hold num_lines * beams_per_line = " + std::to_string(cells) + " points";
    Fail("OrderedScan.points_m", rule.c_str(), points_m.size());
  }
  Require(FinitePositive(pan_step_rad), "OrderedScan.pan_step_rad", "must be > 0", pan_step_rad);
  Require(FinitePositive(tilt_step_rad), "OrderedScan.tilt_step_rad", "must be > 0", tilt_step_rad);
  Require(Finite(sensor_origin_m), "OrderedScan.sensor_origin_m", "must be finite",
          sensor_origin_m.transpose());
  Require(std::isfinite(robot_base_z_m), "OrderedScan.robot_base_z_m", "must be finite",
          robot_base_z_m);
}

void MeshParams::Validate() const {
  Require(std::isfinite(max_side_ratio) && max_side_ratio >= 1.0, "MeshParams.max_side_ratio",
          "must be >= 1", max_side_ratio);
  Require(std::isfinite(max_edge_spacing_ratio) && max_edge_spacing_ratio >= 0.0,
          "MeshParams.max_edge_spacing_ratio", "must be >= 0 (0: off)", max_edge_spacing_ratio);
}

void BuildScanMesh(const OrderedScan& scan, const MeshParams& params, ScanMesh* out) {
  if (out == nullptr) throw std::invalid_argument("BuildScanMesh: the output mesh is null");
  scan.Validate();
  params.Validate();
  const int lines = scan.num_lines;
  const int beams = scan.beams_per_line;
  const int n = scan.size();
  const Eigen::Vector3f* pts = scan.points_m.data();
  const Eigen::Vector3f origin = scan.sensor_origin_m;

  // Every array is refilled in place: a mesh rebuilt scan after scan keeps its capacity.
  ScanMesh& mesh = *out;
  mesh.triangles.clear();
  mesh.rejected_triangles.clear();
  mesh.neighbours.clear();
  mesh.area_per_point_m2.assign(n, 0.f);
  mesh.normals.assign(n, Eigen::Vector3f::Zero());
  // Until the end, neighbour_offsets[i] holds point i's neighbour bits (0: in no accepted
  // triangle).
  mesh.neighbour_offsets.assign(static_cast<size_t>(n) + 1, 0);
  if (lines >= 2 && beams >= 2) {
    mesh.triangles.reserve(2 * static_cast<size_t>(lines - 1) * (beams - 1));
  }
  mesh.neighbours.reserve(6 * static_cast<size_t>(n));

  const float side_ratio2 = static_cast<float>(params.max_side_ratio * params.max_side_ratio);
  const double spacing =
      params.max_edge_spacing_ratio * std::max(scan.pan_step_rad, scan.tilt_step_rad);
  const float edge_k2 = static_cast<float>(spacing * spacing);

  float* par = mesh.area_per_point_m2.data();
  Eigen::Vector3f* nsum = mesh.normals.data();
  int32_t* nmask = mesh.neighbour_offsets.data();
  Accumulator acc{&mesh, par, nsum, nmask, origin, side_ratio2, edge_k2};
  const auto range2 = [&](const Eigen::Vector3f& p, int valid) {
    return valid ? (p - origin).squaredNorm() : 0.f;
  };
  for (int l = 0; l + 1 < lines; ++l) {
    const Eigen::Vector3f* row0 = pts + static_cast<size_t>(l) * beams;
    const Eigen::Vector3f* row1 = row0 + beams;
    // Validity and squared range of corners 0 (l, b) and 1 (l + 1, b), carried along the line.
    int v0 = Finite(row0[0]), v1 = Finite(row1[0]);
    float r0 = range2(row0[0], v0), r1 = range2(row1[0], v1);
    for (int b = 0; b + 1 < beams; ++b) {
      const Eigen::Vector3f& p0 = row0[b];
      const Eigen::Vector3f& p1 = row1[b];
      const Eigen::Vector3f& p2 = row1[b + 1];
      const Eigen::Vector3f& p3 = row0[b + 1];
      const int v3 = Finite(p3), v2 = Finite(p2);
      const float r3 = range2(p3, v3), r2 = range2(p2, v2);
      const int quad = v0 | v1 << 1 | v2 << 2 | v3 << 3;
      const int i0 = l * beams + b, i1 = i0 + beams, i2 = i1 + 1, i3 = i0 + 1;
      if (quad == 15) {
        // Both triangles, (0, 1, 2) and (0, 2, 3), sharing the diagonal 0-2.
        const Eigen::Vector3f e01 = p1 - p0, e02 = p2 - p0, e03 = p3 - p0;
        const Eigen::Vector3f e12 = p2 - p1, e32 = p2 - p3;
        const float l01 = e01.squaredNorm(), l02 = e02.squaredNorm(), l03 = e03.squaredNorm();
        const float l12 = e12.squaredNorm(), l32 = e32.squaredNorm();
        const Eigen::Vector3f ca = e01.cross(e02), cb = e02.cross(e03);
        const float ca2 = ca.squaredNorm(), cb2 = cb.squaredNorm();
        const float r02 = std::min(r0, r2);
        acc.Add(acc.Reject(l01, l12, l02, ca2, std::min(r02, r1)), i0, i1, i2, p0 + p1 + p2, ca,
                ca2, kA0, kA1, kA2);
        acc.Add(acc.Reject(l02, l32, l03, cb2, std::min(r02, r3)), i0, i2, i3, p0 + p2 + p3, cb,
                cb2, kB0, kB2, kB3);
      } else if (kQuadTriangles[quad].count == 1) {
        const std::array<int, 3>& c = kQuadTriangles[quad].corners[0];
        const std::array<const Eigen::Vector3f*, 4> p{&p0, &p1, &p2, &p3};
        const std::array<int, 4> idx{i0, i1, i2, i3};
        const std::array<float, 4> r{r0, r1, r2, r3};
        const Eigen::Vector3f& pa = *p[c[0]];
        const Eigen::Vector3f& pb = *p[c[1]];
        const Eigen::Vector3f& pc = *p[c[2]];
        const Eigen::Vector3f ab = pb - pa, ac = pc - pa, bc = pc - pb;
        const Eigen::Vector3f cross = ab.cross(ac);
        const float cross2 = cross.squaredNorm();
        const bool reject = acc.Reject(ab.squaredNorm(), bc.squaredNorm(), ac.squaredNorm(), cross2,
                                       std::min(r[c[0]], std::min(r[c[1]], r[c[2]])));
        acc.Add(reject, idx[c[0]], idx[c[1]], idx[c[2]], pa + pb + pc, cross, cross2,
                TriangleBits(c, 0), TriangleBits(c, 1), TriangleBits(c, 2));
      }
      v0 = v3;
      v1 = v2;
      r0 = r3;
      r1 = r2;
    }
  }

  // Bits to compressed rows, in increasing neighbour index.
  int32_t running = 0;
  for (int i = 0; i < n; ++i) {
    const int32_t m = nmask[i];
    nmask[i] = running;
    if (m == 0) {
      par[i] = kNaN;
      nsum[i].setConstant(kNaN);
      continue;
    }
    for (int k = 0; k < 8; ++k) {
      if (m & (1 << k)) {
        mesh.neighbours.push_back(i + kBitLine[k] * beams + kBitBeam[k]);
        ++running;
      }
    }
    const float norm = nsum[i].norm();
    if (norm > 0.f) {
      nsum[i] /= norm;
    } else {
      nsum[i].setConstant(kNaN);  // triangles whose oriented normals cancel (degenerate fan)
    }
  }
  nmask[n] = running;
}

ScanMesh BuildScanMesh(const OrderedScan& scan, const MeshParams& params) {
  ScanMesh mesh;
  BuildScanMesh(scan, params, &mesh);
  return mesh;
}

}  // namespace cairn::explore
