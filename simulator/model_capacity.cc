#include "simulator/model_capacity.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <stdexcept>
#include <vector>

namespace cairn::sim {
namespace {

struct GeomInfo {
  int type{mjGEOM_BOX};
  int contype{0};
  int conaffinity{0};
  int condim{3};
  int priority{0};
  int weld{0};  ///< body this geom is welded to (0: the world, mocap bodies included)
  double rbound_m{0.0};
};

GeomInfo Geom(const mjModel* m, int g, int parked_geom_group) {
  GeomInfo info;
  const int body = m->geom_bodyid[g];
  info.type = m->geom_type[g];
  info.contype = m->geom_contype[g];
  info.conaffinity = m->geom_conaffinity[g];
  info.condim = m->geom_condim[g];
  info.priority = m->geom_priority[g];
  info.weld = m->body_weldid[body];
  info.rbound_m = m->geom_rbound[g];
  if (m->geom_group[g] == parked_geom_group) {
    // A spawn-pool slot: at run time a box, cylinder or sphere of up to 50 m that collides
    // with everything (MujocoSim::SpawnObject).
    info.type = mjGEOM_BOX;
    info.contype = 1;
    info.conaffinity = 1;
    info.condim = std::max(info.condim, 3);
  }
  return info;
}

// MuJoCo 2.2's filters: contype/conaffinity, and never two geoms welded to the same body (the
// world's geoms, mocap bodies' included, never touch each other). Its parent-child filter is
// left out: an over-estimate.
bool CanCollide(const GeomInfo& a, const GeomInfo& b) {
  if ((a.contype & b.conaffinity) == 0 && (b.contype & a.conaffinity) == 0) return false;
  return a.weld != b.weld;
}

// Prisms of height field `h` under a geom of bounding radius r (MuJoCo 2.2 collides a geom with
// each prism under its bounding box, one contact per prism).
int HfieldPrisms(const mjModel* m, int h, double r) {
  const double* size = m->hfield_size + 4 * h;
  const int nrow = m->hfield_nrow[h];
  const int ncol = m->hfield_ncol[h];
  const double dx = ncol > 1 ? 2.0 * size[0] / (ncol - 1) : 2.0 * size[0];
  const double dy = nrow > 1 ? 2.0 * size[1] / (nrow - 1) : 2.0 * size[1];
  const double cells_x = std::min<double>(ncol, std::ceil(2.0 * r / std::max(dx, 1e-9)) + 1.0);
  const double cells_y = std::min<double>(nrow, std::ceil(2.0 * r / std::max(dy, 1e-9)) + 1.0);
  const double prisms = 2.0 * cells_x * cells_y;
  return static_cast<int>(std::min<double>(prisms, mjMAXCONPAIR));
}

// The most contacts MuJoCo 2.2 makes between geoms of these types (its collision table).
int PairContacts(const mjModel* m, int ga, const GeomInfo& a, int gb, const GeomInfo& b) {
  if (a.type == mjGEOM_HFIELD || b.type == mjGEOM_HFIELD) {
    const bool a_field = a.type == mjGEOM_HFIELD;
    const int h = m->geom_dataid[a_field ? ga : gb];
    const double r = a_field ? b.rbound_m : a.rbound_m;
    if (h < 0 || r <= 0.0) return mjMAXCONPAIR;  // no size known: the function's limit
    return HfieldPrisms(m, h, r);
  }
  const auto either = [&](int type) { return a.type == type || b.type == type; };
  if (either(mjGEOM_SPHERE) || either(mjGEOM_ELLIPSOID)) return 1;
  if (either(mjGEOM_CAPSULE)) return 2;
  if (either(mjGEOM_BOX)) return 8;       // box-box, plane-box: up to 8 corners
  if (either(mjGEOM_CYLINDER)) return 4;  // plane-cylinder: up to 4
  return 4;                               // meshes (plane-convex: up to 3; convex-convex: 1)
}

// Constraint rows of one contact: the pair's condim (the higher priority geom's, else the
// larger), pyramidal cone.
int RowsPerContact(const GeomInfo& a, const GeomInfo& b) {
  const int condim = a.priority != b.priority ? (a.priority > b.priority ? a.condim : b.condim)
                                              : std::max(a.condim, b.condim);
  return condim <= 1 ? 1 : 2 * (condim - 1);
}

int ClampToInt(double v) {
  return static_cast<int>(std::min<double>(v, std::numeric_limits<int>::max()));
}

}  // namespace

ModelCapacity ContactCapacity(const mjModel* m, int parked_geom_group) {
  std::vector<GeomInfo> geoms;
  geoms.reserve(m->ngeom);
  for (int g = 0; g < m->ngeom; ++g) geoms.push_back(Geom(m, g, parked_geom_group));

  double contacts = 0.0;
  double rows = 0.0;
  // Each moving geom against its kSimultaneousPartners most demanding partners (a pair of two
  // moving geoms is counted from both sides: an over-estimate, never an under-estimate).
  struct Demand {
    int contacts;
    int rows;
  };
  std::vector<Demand> demands;
  for (int g = 0; g < m->ngeom; ++g) {
    const GeomInfo& a = geoms[g];
    // Contacts are counted from the side of geoms on bodies with joints (robots, doors): a
    // mocap body's geoms only touch those, and are counted as their partners.
    if (a.weld == 0 || (a.contype == 0 && a.conaffinity == 0)) continue;
    demands.clear();
    for (int p = 0; p < m->ngeom; ++p) {
      if (p == g || !CanCollide(a, geoms[p])) continue;
      const int n = PairContacts(m, g, a, p, geoms[p]);
      demands.push_back({n, n * RowsPerContact(a, geoms[p])});
    }
    const size_t keep = std::min<size_t>(demands.size(), kSimultaneousPartners);
    std::partial_sort(demands.begin(), demands.begin() + static_cast<std::ptrdiff_t>(keep),
                      demands.end(),
                      [](const Demand& x, const Demand& y) { return x.rows > y.rows; });
    for (size_t i = 0; i < keep; ++i) {
      contacts += demands[i].contacts;
      rows += demands[i].rows;
    }
  }
  // Explicit <pair> elements collide whatever their types' filters say.
  for (int i = 0; i < m->npair; ++i) {
    const int ga = m->pair_geom1[i];
    const int gb = m->pair_geom2[i];
    const int n = PairContacts(m, ga, geoms[ga], gb, geoms[gb]);
    contacts += n;
    const int condim = m->pair_dim[i];
    rows += n * (condim <= 1 ? 1 : 2 * (condim - 1));
  }
  // Other constraints: equality (a weld is 6 rows), joint and tendon limits, friction loss.
  rows += 6.0 * m->neq;
  for (int j = 0; j < m->njnt; ++j) rows += m->jnt_limited[j] ? 1 : 0;
  for (int t = 0; t < m->ntendon; ++t) {
    rows += m->tendon_limited[t] ? 1 : 0;
    rows += m->tendon_frictionloss[t] > 0.0 ? 1 : 0;
  }
  for (int v = 0; v < m->nv; ++v) rows += m->dof_frictionloss[v] > 0.0 ? 1 : 0;

  ModelCapacity capacity;
  capacity.nconmax = std::max(100, ClampToInt(contacts));
  capacity.njmax = std::max(500, ClampToInt(rows));
  capacity.nstack = MujocoStackHeuristic(m, capacity.njmax);
  return capacity;
}

int MujocoStackHeuristic(const mjModel* m, int njmax) {
  const double square = static_cast<double>(njmax) + m->neq + m->nv;
  const double rest = 20.0 * (m->nq + m->nv + m->nu + m->na + m->nbody + m->njnt + m->ngeom +
                              m->nsite + m->neq + m->ntendon + m->nwrap);
  const double n = std::max(1000.0, 5.0 * square * square + rest);
  if (n > std::numeric_limits<int>::max()) {
    throw std::runtime_error("the scene needs a MuJoCo stack of " + std::to_string(n) +
                             " numbers, more than MuJoCo 2.2 can address");
  }
  return static_cast<int>(n);
}

namespace {

// Finds "<size" followed by whitespace, '>' or '/' (comments are expected to be stripped).
size_t FindSizeElement(const std::string& xml) {
  for (size_t pos = xml.find("<size"); pos != std::string::npos; pos = xml.find("<size", pos + 1)) {
    const size_t next = pos + 5;
    if (next >= xml.size()) break;
    const char c = xml[next];
    if (c == '>' || c == '/' || c == ' ' || c == '\t' || c == '\n' || c == '\r') return pos;
  }
  return std::string::npos;
}

bool HasAttribute(const std::string& element, const std::string& name) {
  for (size_t pos = element.find(name); pos != std::string::npos;
       pos = element.find(name, pos + 1)) {
    const char before = pos > 0 ? element[pos - 1] : ' ';
    size_t after = pos + name.size();
    while (after < element.size() && (element[after] == ' ' || element[after] == '\t')) ++after;
    if ((before == ' ' || before == '\t' || before == '\n' || before == '\r') &&
        after < element.size() && element[after] == '=') {
      return true;
    }
  }
  return false;
}

}  // namespace

SizeAttributes SizeAttributesOf(const std::string& xml) {
  SizeAttributes set;
  const size_t size = FindSizeElement(xml);
  if (size == std::string::npos) return set;
  const std::string element = xml.substr(size, xml.find('>', size) - size);
  set.nconmax = HasAttribute(element, "nconmax");
  set.njmax = HasAttribute(element, "njmax");
  set.nstack = HasAttribute(element, "nstack");
  return set;
}

std::string WithSizes(const std::string& xml, const ModelCapacity& sizes,
                      const SizeAttributes& keep) {
  std::string attributes;
  const auto add = [&](const char* name, int value, bool kept) {
    if (!kept && value >= 0)
      attributes += std::string(" ") + name + "=\"" + std::to_string(value) + "\"";
  };
  add("nconmax", sizes.nconmax, keep.nconmax);
  add("njmax", sizes.njmax, keep.njmax);
  add("nstack", sizes.nstack, keep.nstack);
  if (attributes.empty()) return xml;
  const size_t size = FindSizeElement(xml);
  if (size != std::string::npos) return xml.substr(0, size + 5) + attributes + xml.substr(size + 5);
  const size_t open = xml.find("<mujoco");
  const size_t open_end = xml.find('>', open);
  if (open == std::string::npos || open_end == std::string::npos) {
    throw std::invalid_argument("not an MJCF text (no <mujoco> element)");
  }
  return xml.substr(0, open_end + 1) + "\n  <size" + attributes + "/>" + xml.substr(open_end + 1);
}

}  // namespace cairn::sim
