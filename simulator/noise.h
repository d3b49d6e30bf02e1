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
  /// Standard normal sample number `index`.
  double Gaussian(uint64_t index) const;
  /// Uniform sample in [0, 1).
  double Uniform(uint64_t index) const;

 private:
  uint64_t key_{0};
};

/// Stream id for a named noise source of a robot ("rover1/hdl32e").
uint64_t NoiseStream(const std::string& name);

}  // namespace cairn::sim
