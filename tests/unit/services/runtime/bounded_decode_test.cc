// Every cairn message decoder is bounded by the bytes it is given (cmake/BoundLcmDecode.cmake
// post-processes lcm-gen's headers): a count or string length on the wire that the message
// cannot hold is refused, never allocated. Before, one 60-byte lcmt_health whose num_channels
// said 67 million made every subscriber allocate 67 million channel entries, and a negative
// count or a zero string length threw std::length_error through liblcm's C dispatch.

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cairn/lcmt_health.hpp"
#include "cairn/lcmtypes_registry.hpp"

namespace cairn::runtime {
namespace {

// Peak resident memory of this process (kB), from /proc.
int64_t PeakRssKb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stoll(line.substr(6));
  }
  return -1;
}

void PutBigEndian(std::vector<uint8_t>* bytes, size_t at, int32_t value) {
  const uint32_t v = static_cast<uint32_t>(value);
  (*bytes)[at] = static_cast<uint8_t>(v >> 24);
  (*bytes)[at + 1] = static_cast<uint8_t>(v >> 16);
  (*bytes)[at + 2] = static_cast<uint8_t>(v >> 8);
  (*bytes)[at + 3] = static_cast<uint8_t>(v);
}

// Every type, its empty message with each 4-byte word in turn set to a count no message of
// that size can hold (67 million, INT32_MAX), to a negative count and to 0 (a string length
// below the 1 its NUL takes): each decode refuses or succeeds within the bytes, never throws,
// and all of them together leave the peak memory where it was.
TEST(BoundedDecodeTest, NoCountOrLengthOnTheWireAllocatesBeyondTheMessage) {
  const int64_t peak_before = PeakRssKb();
  ASSERT_GT(peak_before, 0);
  int refused = 0;
  for (const cairn::LcmTypeInfo& type : cairn::AllLcmTypes()) {
    const std::vector<uint8_t> sample = type.sample();
    ASSERT_GT(type.decode(sample.data(), static_cast<int>(sample.size())), 0) << type.name;
    for (size_t at = 8; at + 4 <= sample.size(); ++at) {
      for (int32_t value : {67'108'864, INT32_MAX, -1, -67'108'864, 0}) {
        std::vector<uint8_t> bytes = sample;
        PutBigEndian(&bytes, at, value);
        int n = 0;
        EXPECT_NO_THROW(n = type.decode(bytes.data(), static_cast<int>(bytes.size())))
            << type.name << " word at " << at << " = " << value;
        EXPECT_LE(n, static_cast<int>(bytes.size()));
        refused += n < 0;
      }
    }
  }
  EXPECT_GT(refused, 100);
  EXPECT_LT(PeakRssKb() - peak_before, 50 * 1024) << "a decode allocated what the bytes lacked";
}

// The finding itself: a heartbeat with empty strings is 84 bytes with its fingerprint; its
// num_channels word (after 8 + 8 + 8 + 5 + 5 + 4 + 1 + 8 + 8 + 8 + 8 + 5 bytes) says 67,108,864.
TEST(BoundedDecodeTest, AHeartbeatClaimingSixtySevenMillionChannelsIsRefused) {
  cairn::lcmt_health h{};
  std::vector<uint8_t> bytes(h.getEncodedSize());
  ASSERT_EQ(h.encode(bytes.data(), 0, static_cast<int>(bytes.size())), 84);
  const size_t num_channels_at = 8 + 8 + 8 + 5 + 5 + 4 + 1 + 8 + 8 + 8 + 8 + 5;
  cairn::lcmt_health d;
  ASSERT_EQ(d.decode(bytes.data(), 0, static_cast<int>(bytes.size())), 84);
  PutBigEndian(&bytes, num_channels_at, 67'108'864);
  const int64_t peak_before = PeakRssKb();
  EXPECT_EQ(d.decode(bytes.data(), 0, static_cast<int>(bytes.size())), -1);
  EXPECT_LT(PeakRssKb() - peak_before, 10 * 1024);
  PutBigEndian(&bytes, num_channels_at, -1);
  EXPECT_EQ(d.decode(bytes.data(), 0, static_cast<int>(bytes.size())), -1);
}

}  // namespace
}  // namespace cairn::runtime
