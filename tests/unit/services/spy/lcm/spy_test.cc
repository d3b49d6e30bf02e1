#include "services/spy/lcm/spy.h"

#include <gtest/gtest.h>

#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmtypes_registry.hpp"

namespace cairn::spy {
namespace {

std::vector<uint8_t> Encode(const cairn::lcmt_pose& m) {
  std::vector<uint8_t> b(m.getEncodedSize());
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

TEST(SpyTest, NamesEveryGeneratedTypeByFingerprint) {
  Spy dut;
  for (const auto& t : cairn::AllLcmTypes()) {
    const auto bytes = t.sample();
    dut.OnMessage(std::string("CH.") + t.name, bytes.data(), static_cast<int>(bytes.size()), 0.0);
  }
  const auto views = dut.Snapshot(0.1);
  ASSERT_EQ(views.size(), cairn::AllLcmTypes().size());
  for (const auto& [channel, v] : views) {
    EXPECT_EQ("CH." + v.type, channel);
    EXPECT_EQ(v.decode_errors, 0);
  }
}

TEST(SpyTest, CountsTruncatedAndForeignMessages) {
  Spy dut;
  cairn::lcmt_pose pose{};
  pose.robot = "r";
  auto bytes = Encode(pose);
  dut.OnMessage("r.POSE", bytes.data(), static_cast<int>(bytes.size()), 0.0);
  dut.OnMessage("r.POSE", bytes.data(), static_cast<int>(bytes.size()) / 2, 0.1);
  const uint8_t foreign[16] = {0xde, 0xad, 0xbe, 0xef, 1, 2, 3, 4, 5, 6, 7, 8};
  dut.OnMessage("OTHER", foreign, sizeof(foreign), 0.2);
  auto views = dut.Snapshot(0.3);
  EXPECT_EQ(views["r.POSE"].type, "cairn.lcmt_pose");
  EXPECT_EQ(views["r.POSE"].decode_errors, 1);
  EXPECT_EQ(views["OTHER"].type.rfind("? (fingerprint 0xdeadbeef", 0), 0u);
  EXPECT_EQ(views["OTHER"].decode_errors, 1);
}

TEST(SpyTest, FlagsSlowAndMissingChannels) {
  Spy dut({{"fast.CH", 10.0}, {"never.CH", 5.0}});
  cairn::lcmt_pose pose{};
  const auto bytes = Encode(pose);
  for (int i = 0; i <= 20; ++i) dut.OnMessage("fast.CH", bytes.data(), static_cast<int>(bytes.size()), i * 0.1);
  auto views = dut.Snapshot(2.0);
  EXPECT_NEAR(views["fast.CH"].rate.rate_hz, 10.0, 0.6);
  EXPECT_FALSE(views["fast.CH"].slow);
  EXPECT_TRUE(views["never.CH"].slow);
  EXPECT_EQ(views["never.CH"].type, "(not seen)");
  EXPECT_NE(dut.Format(2.0).find("<< SLOW"), std::string::npos);
}

}  // namespace
}  // namespace cairn::spy
