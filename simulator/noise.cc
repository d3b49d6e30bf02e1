#include "simulator/noise.h"

#include <array>
#include <cmath>

#include "common/robot_profile.h"

namespace cairn::sim {
namespace {

// SplitMix64: a strong 64-bit mixer, enough for simulation noise.
uint64_t Mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

double ToUnit(uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

constexpr int kQuantileBits = 12;
constexpr int kQuantiles = 1 << kQuantileBits;

// Standard normal quantiles at (i + 0.5) / (kQuantiles + 1), i = 0..kQuantiles.
const std::array<double, kQuantiles + 1>& QuantileTable() {
  static const std::array<double, kQuantiles + 1> table = [] {
    std::array<double, kQuantiles + 1> t{};
    for (int i = 0; i <= kQuantiles; ++i) {
      const double p = (i + 0.5) / (kQuantiles + 1);
      // Bisection on the CDF 0.5 * erfc(-x / sqrt(2)).
      double lo = -10.0, hi = 10.0;
      for (int k = 0; k < 100; ++k) {
        const double mid = 0.5 * (lo + hi);
        if (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p) {
          lo = mid;
        } else {
          hi = mid;
        }
      }
      t[i] = 0.5 * (lo + hi);
    }
    return t;
  }();
  return table;
}

}  // namespace

NoiseSource::NoiseSource(uint64_t seed, uint64_t stream) : key_(Mix(Mix(seed) ^ stream)) {}

double NoiseSource::Uniform(uint64_t index) const { return ToUnit(Mix(key_ ^ Mix(index))); }

double NoiseSource::Gaussian(uint64_t index) const {
  // Inverse-CDF sampling: the top 12 bits of one hash pick a cell of the quantile table, the
  // next 32 bits interpolate inside it. No transcendental functions per sample (a lidar draws
  // half a million samples per simulated second); tails are clipped at |z| = 3.67.
  const std::array<double, kQuantiles + 1>& table = QuantileTable();
  const uint64_t h = Mix(key_ ^ (index * 0xd1b54a32d192ed03ULL));
  const uint64_t cell = h >> (64 - kQuantileBits);
  const double frac =
      static_cast<double>((h >> (64 - kQuantileBits - 32)) & 0xffffffffULL) * 0x1.0p-32;
  return table[cell] + (table[cell + 1] - table[cell]) * frac;
}

uint64_t NoiseStream(const std::string& name) { return common::Fnv1a64(name.data(), name.size()); }

}  // namespace cairn::sim
