#include "planner/global/dubins_space.h"

#include <algorithm>
#include <cmath>

namespace cairn::planner {

namespace ob = ompl::base;

namespace {

constexpr double kTwoPi = 2.0 * M_PI;

// Angle in [0, 2π); values a hair below 2π become 0 so that a path does not gain a full loop
// from rounding.
double Mod2Pi(double x) {
  double m = x - kTwoPi * std::floor(x / kTwoPi);
  if (kTwoPi - m < 1e-9) m = 0.0;
  return m;
}

struct Word {
  int type{-1};  // index into DubinsStateSpace::dubinsPathType, -1 when infeasible
  double t{0.0}, p{0.0}, q{0.0};
  double length() const { return t + p + q; }
};

// The six words for a unit turning radius, start at the origin heading alpha, goal at (d, 0)
// heading beta (angles relative to the line between them).
Word Solve(int type, double d, double alpha, double beta) {
  const double sa = std::sin(alpha), ca = std::cos(alpha);
  const double sb = std::sin(beta), cb = std::cos(beta);
  const double c_ab = ca * cb + sa * sb;  // cos(alpha - beta)
  Word w;
  switch (type) {
    case 0: {  // LSL
      const double p2 = 2.0 + d * d - 2.0 * c_ab + 2.0 * d * (sa - sb);
      if (p2 < 0.0) return w;
      const double theta = std::atan2(cb - ca, d + sa - sb);
      w = {type, Mod2Pi(theta - alpha), std::sqrt(p2), Mod2Pi(beta - theta)};
      break;
    }
    case 1: {  // RSR
      const double p2 = 2.0 + d * d - 2.0 * c_ab + 2.0 * d * (sb - sa);
      if (p2 < 0.0) return w;
      const double theta = std::atan2(ca - cb, d - sa + sb);
      w = {type, Mod2Pi(alpha - theta), std::sqrt(p2), Mod2Pi(theta - beta)};
      break;
    }
    case 2: {  // RSL
      const double p2 = d * d - 2.0 + 2.0 * c_ab - 2.0 * d * (sa + sb);
      if (p2 < 0.0) return w;
      const double p = std::sqrt(p2);
      const double theta = std::atan2(ca + cb, d - sa - sb) - std::atan2(2.0, p);
      w = {type, Mod2Pi(alpha - theta), p, Mod2Pi(beta - theta)};
      break;
    }
    case 3: {  // LSR
      const double p2 = d * d - 2.0 + 2.0 * c_ab + 2.0 * d * (sa + sb);
      if (p2 < 0.0) return w;
      const double p = std::sqrt(p2);
      const double theta = std::atan2(-ca - cb, d + sa + sb) - std::atan2(-2.0, p);
      w = {type, Mod2Pi(theta - alpha), p, Mod2Pi(theta - beta)};
      break;
    }
    case 4: {  // RLR
      const double c = (6.0 - d * d + 2.0 * c_ab + 2.0 * d * (sa - sb)) / 8.0;
      if (std::abs(c) >= 1.0) return w;
      const double p = kTwoPi - std::acos(c);
      const double theta = std::atan2(ca - cb, d - sa + sb);
      const double t = Mod2Pi(alpha - theta + 0.5 * p);
      w = {type, t, p, Mod2Pi(alpha - beta - t + p)};
      break;
    }
    case 5: {  // LRL
      const double c = (6.0 - d * d + 2.0 * c_ab - 2.0 * d * (sa - sb)) / 8.0;
      if (std::abs(c) >= 1.0) return w;
      const double p = kTwoPi - std::acos(c);
      const double theta = std::atan2(cb - ca, d + sa - sb);
      const double t = Mod2Pi(theta - alpha + 0.5 * p);
      w = {type, t, p, Mod2Pi(beta - alpha - t + p)};
      break;
    }
    default:
      break;
  }
  return w;
}

}  // namespace

ob::DubinsStateSpace::DubinsPath DubinsSpace::ShortestPath(const ob::State* a,
                                                           const ob::State* b) const {
  const auto* s1 = a->as<StateType>();
  const auto* s2 = b->as<StateType>();
  const double dx = s2->getX() - s1->getX();
  const double dy = s2->getY() - s1->getY();
  const double d = std::hypot(dx, dy) / rho_;
  const double heading = std::atan2(dy, dx);
  const double alpha = Mod2Pi(s1->getYaw() - heading);
  const double beta = Mod2Pi(s2->getYaw() - heading);
  if (d < 1e-6 && std::abs(alpha - beta) < 1e-6) return DubinsPath(dubinsPathType[0], 0.0, d, 0.0);
  Word best;
  for (int type = 0; type < 6; ++type) {
    const Word w = Solve(type, d, alpha, beta);
    if (w.type >= 0 && (best.type < 0 || w.length() < best.length())) best = w;
  }
  if (best.type < 0) return DubinsPath();  // cannot happen: LSL or RSR always exists
  return DubinsPath(dubinsPathType[best.type], best.t, best.p, best.q);
}

double DubinsSpace::distance(const ob::State* a, const ob::State* b) const {
  return rho_ * ShortestPath(a, b).length();
}

void DubinsSpace::interpolate(const ob::State* from, const ob::State* to, double t,
                              ob::State* state) const {
  bool first_time = true;
  DubinsPath path;
  interpolate(from, to, t, first_time, path, state);
}

void DubinsSpace::interpolate(const ob::State* from, const ob::State* to, double t,
                              bool& first_time, DubinsPath& path, ob::State* state) const {
  if (first_time) {
    if (t >= 1.0) {
      copyState(state, to);
      return;
    }
    copyState(state, from);
    if (t <= 0.0) return;
    path = ShortestPath(from, to);
    first_time = false;
  }
  DubinsStateSpace::interpolate(from, path, t, state);
}

}  // namespace cairn::planner
