#include "services/launch/status.h"

#include <gtest/gtest.h>

namespace cairn::launch {
namespace {

TEST(StatusTest, JsonRoundTripAndTable) {
  GraphStatus s;
  s.graph = "demo";
  s.file = "config/graphs/demo.yaml";
  s.lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  s.launcher_pid = 42;
  s.state = "ready";
  s.message = "a \"quoted\" message";
  ProcessRow row;
  row.name = "sim";
  row.robot = "rover1";
  row.state = "ready";
  row.pid = 77;
  row.restarts = 2;
  row.cpu_percent = 55.5;
  row.rss_mb = 120.25;
  row.channels_hz["rover1.LIDAR"] = 180.0;
  s.processes.push_back(row);
  s.channel_rates_hz["rover1.LIDAR"] = 100.0;
  s.expected_rates_hz["rover1.LIDAR"] = 180.0;
  std::string error;
  auto back = ParseStatus(ToJson(s), &error);
  ASSERT_TRUE(back.has_value()) << error;
  EXPECT_EQ(back->message, s.message);
  ASSERT_EQ(back->processes.size(), 1u);
  EXPECT_EQ(back->processes[0].restarts, 2);
  EXPECT_NEAR(back->processes[0].rss_mb, 120.25, 1e-3);
  EXPECT_NEAR(back->processes[0].channels_hz.at("rover1.LIDAR"), 180.0, 1e-6);
  const std::string table = FormatStatusTable(*back);
  EXPECT_NE(table.find("sim"), std::string::npos);
  EXPECT_NE(table.find("<< SLOW"), std::string::npos);  // 100 Hz < 80 % of 180 Hz
  EXPECT_FALSE(ParseStatus("{\"x\": 1}", &error).has_value());
  EXPECT_FALSE(ParseStatus("not json {", &error).has_value());
}

}  // namespace
}  // namespace cairn::launch
