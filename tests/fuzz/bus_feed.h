#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "services/runtime/node.h"
#include "tests/fuzz/fuzz_input.h"

/// @file
/// Framed messages fed to a node on memq:// (an in-process bus), so a message reaches a service
/// through the same decode and handler as from the network.

namespace cairn::fuzz {

/// A fuzz input as bus traffic: repeated frames of [channel index: 1 byte][size: 4 bytes, little
/// endian][payload]; the index picks from `channels` (modulo). Each message is published on the
/// node's memq:// bus and handled before the next, with the node's timers (and `after_each`,
/// when given) run between.
inline void FeedBus(runtime::Node& node, const std::vector<std::string>& channels,
                    const uint8_t* data, size_t size,
                    const std::function<void()>& after_each = {}) {
  ByteReader in(data, size);
  while (!in.empty()) {
    const std::string& channel = channels[in.Read<uint8_t>() % channels.size()];
    const uint32_t declared = in.Read<uint32_t>();
    const size_t n = std::min<size_t>(declared, in.remaining());
    std::string payload(n, '\0');
    for (size_t i = 0; i < n; ++i) payload[i] = static_cast<char>(in.Read<uint8_t>());
    node.lcm().publish(channel, payload.data(), static_cast<unsigned>(payload.size()));
    // Handle it, and what the service published in answer (memq queues both).
    for (int i = 0; i < 64 && node.lcm().handleTimeout(0) > 0; ++i) {
    }
    node.SpinOnce(0);
    if (after_each) after_each();
  }
}

/// A frame for FeedBus (the corpus tool writes seeds with it).
inline void AppendFrame(uint8_t channel_index, const void* payload, size_t size, std::string* out) {
  out->push_back(static_cast<char>(channel_index));
  const auto n = static_cast<uint32_t>(size);
  out->append(reinterpret_cast<const char*>(&n), sizeof(n));
  out->append(static_cast<const char*>(payload), size);
}

}  // namespace cairn::fuzz
