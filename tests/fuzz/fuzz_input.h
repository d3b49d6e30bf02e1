#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

/// @file
/// A reader that turns the fuzzer's bytes into values (the bus targets frame messages with it:
/// bus_feed.h).

namespace cairn::fuzz {

/// Reads values from the fuzzer's bytes; past the end every read gives zeros.
class ByteReader {
 public:
  ByteReader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  bool empty() const { return pos_ >= size_; }
  size_t remaining() const { return size_ - pos_; }
  template <typename T>
  T Read() {
    T value{};
    const size_t n = std::min(sizeof(T), remaining());
    if (n > 0) std::memcpy(&value, data_ + pos_, n);
    pos_ += n;
    return value;
  }
  /// An integer in [lo, hi].
  int64_t Range(int64_t lo, int64_t hi) {
    const auto raw = Read<uint32_t>();
    return hi <= lo ? lo : lo + static_cast<int64_t>(raw % static_cast<uint64_t>(hi - lo + 1));
  }
  /// Up to `max` bytes.
  std::string Bytes(size_t max) {
    const size_t n = std::min<size_t>(Read<uint32_t>() % (max + 1), remaining());
    std::string out(reinterpret_cast<const char*>(data_ + pos_), n);
    pos_ += n;
    return out;
  }
  /// The rest.
  std::string Rest() {
    std::string out(reinterpret_cast<const char*>(data_ + pos_), remaining());
    pos_ = size_;
    return out;
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_{0};
};

}  // namespace cairn::fuzz
