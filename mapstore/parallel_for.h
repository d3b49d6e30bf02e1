#pragma once

#include <cstddef>
#include <functional>

/// @file
/// A parallel loop on kept helper threads (the map store compresses and decodes tiles on them).

namespace cairn::mapstore {

/// Runs fn(i) for every i in [0, n) on up to `threads` threads (the caller's among them).
/// The first exception thrown by fn is rethrown in the caller after all threads finished. The
/// helper threads are kept for the next call (one caller at a time; a concurrent caller starts
/// its own).
void ParallelFor(size_t n, int threads, const std::function<void(size_t)>& fn);

}  // namespace cairn::mapstore
