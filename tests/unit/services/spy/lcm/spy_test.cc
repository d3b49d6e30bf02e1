#include "services/spy/lcm/spy.h"

#include <gtest/gtest.h>

#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_sim_clock.hpp"

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
  for (int i = 0; i <= 20; ++i)
    dut.OnMessage("fast.CH", bytes.data(), static_cast<int>(bytes.size()), i * 0.1);
  auto views = dut.Snapshot(2.0);
  EXPECT_NEAR(views["fast.CH"].rate.rate_hz, 10.0, 0.6);
  EXPECT_FALSE(views["fast.CH"].slow);
  EXPECT_TRUE(views["never.CH"].slow);
  EXPECT_EQ(views["never.CH"].type, "(not seen)");
  EXPECT_NE(dut.Format(2.0).find("<< SLOW"), std::string::npos);
}

TEST(SpyTest, ReadsTheTrueRateOfALiveChannelAndDecaysAQuietOne) {
  // 2 Hz over a 3 s window: six or seven messages. Counting n - 1 intervals over the whole
  // window would read 1.67 Hz, within a jitter of SLOW.
  Spy dut({{"slow2.CH", 2.0}}, 3.0);
  cairn::lcmt_pose pose{};
  const auto bytes = Encode(pose);
  for (int i = 0; i <= 20; ++i)
    dut.OnMessage("slow2.CH", bytes.data(), static_cast<int>(bytes.size()), i * 0.5);
  for (const double now : {10.0, 10.2, 10.45}) {
    auto views = dut.Snapshot(now);
    EXPECT_NEAR(views["slow2.CH"].rate.rate_hz, 2.0, 0.05) << now;
    EXPECT_FALSE(views["slow2.CH"].slow) << now;
  }
  // Quiet for two seconds: the open interval counts, the rate falls below 80 %.
  auto views = dut.Snapshot(12.0);
  EXPECT_LT(views["slow2.CH"].rate.rate_hz, 1.6);
  EXPECT_TRUE(views["slow2.CH"].slow);
}

TEST(SpyTest, JudgesExpectedRatesAtTheSimulatorsPace) {
  Spy dut({{"r.ODOM", 10.0}}, 5.0);
  cairn::lcmt_pose pose{};
  const auto bytes = Encode(pose);
  auto clock_at = [&](double wall_s, double sim_s) {
    cairn::lcmt_sim_clock c{};
    c.utime = static_cast<int64_t>(sim_s * 1e6);
    std::vector<uint8_t> b(c.getEncodedSize());
    c.encode(b.data(), 0, static_cast<int>(b.size()));
    dut.OnMessage("SIM.CLOCK", b.data(), static_cast<int>(b.size()), wall_s);
  };
  // The simulator runs at 0.6x real time: a 10 Hz (simulated) channel arrives at 6 Hz.
  for (int i = 0; i <= 50; ++i) {
    const double wall = i * 0.1;
    clock_at(wall, 0.6 * wall);
  }
  for (int i = 0; i <= 30; ++i)
    dut.OnMessage("r.ODOM", bytes.data(), static_cast<int>(bytes.size()), i / 6.0);
  const SimPace pace = dut.Pace(5.0);
  ASSERT_TRUE(pace.known);
  EXPECT_NEAR(pace.real_time_factor, 0.6, 0.01);
  auto views = dut.Snapshot(5.0);
  EXPECT_NEAR(views["r.ODOM"].rate.rate_hz, 6.0, 0.1);
  EXPECT_FALSE(views["r.ODOM"].slow);
  EXPECT_NE(dut.Format(5.0).find("simulated time at 0.60x real time"), std::string::npos);

  // Without a clock, 6 Hz against 10 Hz is slow.
  Spy no_clock({{"r.ODOM", 10.0}}, 5.0);
  for (int i = 0; i <= 30; ++i)
    no_clock.OnMessage("r.ODOM", bytes.data(), static_cast<int>(bytes.size()), i / 6.0);
  EXPECT_FALSE(no_clock.Pace(5.0).known);
  EXPECT_TRUE(no_clock.Snapshot(5.0)["r.ODOM"].slow);
}

}  // namespace
}  // namespace cairn::spy
