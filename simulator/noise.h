#pragma once

#include <cstdint>
#include <string>

/// @file
/// Counter-based noise for the simulated sensors: no hidden state, so runs with the same seed
/// repeat exactly whatever the thread count and the order in which samples are drawn.

namespace cairn::sim {

/// The value for (seed, stream, index) is fixed, whichever thread asks and in whatever order.
class NoiseSource {
 public:
  NoiseSource() = default;
  NoiseSource(uint64_t seed, uint64_t stream);
  /// Standard normal sample number `index`. Inverse-CDF sampling: the top 12 bits of one hash
  /// pick a cell of the quantile table, the next 32 bits interpolate inside it. No
  /// transcendental function per sample, and inline: a lidar draws half a million samples per
  /// simulated second. Tails are clipped at |z| = 3.67.
  double Gaussian(uint64_t index) const {
    const uint64_t h = Mix(key_ ^ (index * 0xd1b54a32d192ed03ULL));
    const uint64_t cell = h >> (64 - kQuantileBits);
    const double frac =
        static_cast<double>((h >> (64 - kQuantileBits - 32)) & 0xffffffffULL) * 0x1.0p-32;
    return table_[cell] + (table_[cell + 1] - table_[cell]) * frac;
  }
  /// Uniform sample in [0, 1).
  double Uniform(uint64_t index) const;

 private:
  /// SplitMix64: a strong 64-bit mixer, enough for simulation noise.
  static uint64_t Mix(uint64_t x) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
  }
  static constexpr int kQuantileBits = 12;
  /// Standard normal quantiles at (i + 0.5) / (2^kQuantileBits + 1), i = 0..2^kQuantileBits.
  static const double* QuantileTable();

  uint64_t key_{0};
  const double* table_{QuantileTable()};
};

/// Stream id for a named noise source of a robot ("rover1/hdl32e").
uint64_t NoiseStream(const std::string& name);

}  // namespace cairn::sim
