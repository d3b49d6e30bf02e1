#include "simulator/noise.h"

#include <array>
#include <cmath>

#include "common/robot_profile.h"

namespace cairn::sim {
namespace {

double ToUnit(uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

constexpr int kQuantiles = 1 << 12;

const std::array<double, kQuantiles + 1>& Quantiles() {
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

const double* NoiseSource::QuantileTable() {
  static_assert(kQuantiles == 1 << kQuantileBits);
  return Quantiles().data();
}

NoiseSource::NoiseSource(uint64_t seed, uint64_t stream) : key_(Mix(Mix(seed) ^ stream)) {}

double NoiseSource::Uniform(uint64_t index) const { return ToUnit(Mix(key_ ^ Mix(index))); }

uint64_t NoiseStream(const std::string& name) { return common::Fnv1a64(name.data(), name.size()); }

}  // namespace cairn::sim
