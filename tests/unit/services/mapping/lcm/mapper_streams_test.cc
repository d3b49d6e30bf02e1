// The registered sensor streams: one converter per stream (the service subscribes to those the
// layers take; MapperServiceTest.PublishesALayerAddedThroughTheSeam runs one end to end).

#include "services/mapping/lcm/mapper_streams.h"

#include <cmath>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "cairn/lcmt_laser_scan.hpp"
#include "cairn/lcmt_sonar_ping.hpp"

#include "services/mapping/explore_mapper_layer.h"
#include "services/mapping/sonar_mapper_layer.h"

namespace cairn::mapping {
namespace {

TEST(MapperStreamsTest, OneConverterPerStream) {
  std::set<std::string> streams;
  for (const StreamConverter& c : RegisteredStreams()) {
    EXPECT_FALSE(c.stream.empty());
    EXPECT_TRUE(static_cast<bool>(c.convert)) << c.stream;
    EXPECT_TRUE(streams.insert(c.stream).second) << c.stream << " is registered twice";
    // Bytes that are no message are refused, never a crash.
    const char garbage[] = "not a message";
    EXPECT_FALSE(c.convert(garbage, sizeof(garbage)).ok()) << c.stream;
  }
}

const StreamConverter& Converter(const std::string& stream) {
  for (const StreamConverter& c : RegisteredStreams()) {
    if (c.stream == stream) return c;
  }
  throw std::runtime_error("no " + stream + " converter");
}
const StreamConverter& Turret() { return Converter("TURRET_SCAN"); }

template <typename Msg>
std::vector<uint8_t> Encode(const Msg& m) {
  std::vector<uint8_t> bytes(static_cast<size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

cairn::lcmt_laser_scan TurretLine(double pan_rad) {
  cairn::lcmt_laser_scan m{};
  m.utime = 1000000;
  m.robot = "rover";
  m.sensor_position_m[2] = 1.0;
  m.sensor_orientation_wxyz[0] = 1.0;
  m.angle_min_rad = -2.0f;
  m.angle_increment_rad = 0.01f;
  m.range_min_m = 0.1f;
  m.range_max_m = 30.0f;
  m.ranges_m.assign(400, 5.0f);
  m.num_ranges = 400;
  m.turret_angle_rad = pan_rad;
  return m;
}

// A turret line becomes a reading with its pan and its line; a line with a bad pan or arrays
// that disagree with their counts is refused with the reason.
TEST(MapperStreamsTest, TurretLinesAreCheckedBeforeTheyBecomeReadings) {
  const StreamConverter& c = Turret();
  const auto good = Encode(TurretLine(0.25));
  auto reading = c.convert(good.data(), static_cast<int>(good.size()));
  ASSERT_TRUE(reading.ok()) << reading.status().message();
  const auto* line = dynamic_cast<const TurretLineReading*>(reading.value().get());
  ASSERT_NE(line, nullptr);
  EXPECT_DOUBLE_EQ(line->pan_rad, 0.25);
  EXPECT_EQ(line->line.ranges_m.size(), 400u);
  EXPECT_EQ(line->utime, 1000000);
  for (const double pan : {static_cast<double>(NAN), 7.0, -7.0}) {
    const auto bad = Encode(TurretLine(pan));
    auto refused = c.convert(bad.data(), static_cast<int>(bad.size()));
    ASSERT_FALSE(refused.ok()) << pan;
    EXPECT_NE(refused.status().message().find("turret angle"), std::string::npos);
  }
  cairn::lcmt_laser_scan nan_pose = TurretLine(0.0);
  nan_pose.sensor_position_m[0] = NAN;
  const auto bad_pose = Encode(nan_pose);
  EXPECT_FALSE(c.convert(bad_pose.data(), static_cast<int>(bad_pose.size())).ok());
  // Cut short: the bytes end inside the ranges.
  EXPECT_FALSE(c.convert(good.data(), static_cast<int>(good.size()) - 100).ok());
}

cairn::lcmt_sonar_ping SonarPing() {
  cairn::lcmt_sonar_ping m{};
  m.utime = 2000000;
  m.robot = "auv";
  m.frame = "sonar";
  m.sensor_position_m[2] = -5.0;
  m.sensor_orientation_wxyz[0] = 1.0;
  m.pan_rad = 0.3;
  m.range_max_m = 50.0;
  m.sound_speed_mps = 1500.0;
  m.num_bins = 50;
  m.intensities.assign(50, 0);
  m.intensities[10] = 247;
  return m;
}

// A sonar ping becomes a reading with its bins and range; a wrong bin count, a head angle
// beyond pi or not finite, a bad range or pose is refused with the reason (the service counts
// and drops it).
TEST(MapperStreamsTest, SonarPingsAreCheckedBeforeTheyBecomeReadings) {
  const StreamConverter& c = Converter("SONAR");
  const auto good = Encode(SonarPing());
  auto reading = c.convert(good.data(), static_cast<int>(good.size()));
  ASSERT_TRUE(reading.ok()) << reading.status().message();
  const auto* ping = dynamic_cast<const SonarReading*>(reading.value().get());
  ASSERT_NE(ping, nullptr);
  EXPECT_EQ(ping->bins.size(), 50u);
  EXPECT_EQ(ping->bins[10], 247);
  EXPECT_DOUBLE_EQ(ping->pan_rad, 0.3);
  EXPECT_DOUBLE_EQ(ping->range_max_m, 50.0);
  auto refused = [&](cairn::lcmt_sonar_ping m, const std::string& why) {
    const auto bytes = Encode(m);
    auto r = c.convert(bytes.data(), static_cast<int>(bytes.size()));
    ASSERT_FALSE(r.ok()) << why;
    EXPECT_NE(r.status().message().find(why), std::string::npos) << r.status().message();
  };
  cairn::lcmt_sonar_ping m = SonarPing();
  m.num_bins = 0;
  m.intensities.clear();
  refused(m, "bins");
  m = SonarPing();
  m.num_bins = 20000;
  m.intensities.assign(20000, 1);
  refused(m, "bins");
  m = SonarPing();
  m.pan_rad = 4.0;
  refused(m, "angle");
  m.pan_rad = NAN;
  refused(m, "angle");
  m = SonarPing();
  m.range_max_m = NAN;
  refused(m, "range");
  m = SonarPing();
  m.sensor_orientation_wxyz[0] = NAN;
  refused(m, "pose");
  // Cut short: a count that claims more bytes than there are does not decode.
  EXPECT_FALSE(c.convert(good.data(), static_cast<int>(good.size()) - 20).ok());
  // A count of two billion in a 150-byte message is refused before anything is sized by it:
  // num_bins is the int32 just before the 50 bins.
  auto hostile = good;
  const size_t at = hostile.size() - 50 - 4;
  hostile[at] = 0x7f;
  hostile[at + 1] = hostile[at + 2] = hostile[at + 3] = 0xff;
  auto bomb = c.convert(hostile.data(), static_cast<int>(hostile.size()));
  ASSERT_FALSE(bomb.ok());
  EXPECT_NE(bomb.status().message().find("2147483647 bins"), std::string::npos)
      << bomb.status().message();
}

}  // namespace
}  // namespace cairn::mapping
