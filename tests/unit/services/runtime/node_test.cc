#include "services/runtime/node.h"

#include <cstdlib>

#include <gtest/gtest.h>

#include "cairn/lcmt_goal.hpp"
#include "cairn/lcmt_velocity_command.hpp"
#include "common/channels.h"
#include "tests/support/memq_node.h"

namespace cairn::runtime {
namespace {

NodeOptions MemqOptions() {
  return cairn::testing::MemqNodeOptions("node-test", "r1", /*follow_sim_clock=*/true);
}

void SpinFor(Node& node, int rounds) {
  for (int i = 0; i < rounds; ++i) node.SpinOnce(0);
}

TEST(ResolveLcmUrlTest, DefaultsAndTtl) {
  unsetenv("LCM_DEFAULT_URL");
  EXPECT_EQ(ResolveLcmUrl(""), kDefaultLcmUrl);
  EXPECT_EQ(ResolveLcmUrl("udpm://239.255.76.67:7700"), "udpm://239.255.76.67:7700?ttl=0");
  EXPECT_EQ(ResolveLcmUrl("udpm://239.255.76.67:7700?recv_buf_size=100"),
            "udpm://239.255.76.67:7700?recv_buf_size=100&ttl=0");
  setenv("LCM_DEFAULT_URL", "memq://", 1);
  EXPECT_EQ(ResolveLcmUrl(""), "memq://");
  EXPECT_EQ(ResolveLcmUrl("udpm://239.255.76.67:7701?ttl=0"), "udpm://239.255.76.67:7701?ttl=0");
  unsetenv("LCM_DEFAULT_URL");
  EXPECT_THROW(ResolveLcmUrl("bogus"), std::invalid_argument);
  EXPECT_THROW(ResolveLcmUrl("http://x"), std::invalid_argument);
}

TEST(NodeTest, TypedRoundTripAndCounts) {
  Node node(MemqOptions());
  int received = 0;
  double last_v = 0;
  node.Subscribe<cairn::lcmt_velocity_command>("r1.CMD_VEL", [&](const cairn::lcmt_velocity_command& m) {
    ++received;
    last_v = m.linear_mps;
  });
  cairn::lcmt_velocity_command cmd{};
  cmd.linear_mps = 0.25;
  ASSERT_TRUE(node.Publish("r1.CMD_VEL", cmd));
  SpinFor(node, 3);
  EXPECT_EQ(received, 1);
  EXPECT_DOUBLE_EQ(last_v, 0.25);
  const auto health = node.MakeHealth();
  EXPECT_EQ(health.process, "node-test");
  EXPECT_EQ(health.robot, "r1");
  EXPECT_EQ(health.decode_errors, 0);
  bool found_in = false, found_out = false;
  for (const auto& c : health.channels) {
    if (c.channel == "r1.CMD_VEL" && !c.outgoing) found_in = c.messages == 1;
    if (c.channel == "r1.CMD_VEL" && c.outgoing) found_out = c.messages == 1;
  }
  EXPECT_TRUE(found_in);
  EXPECT_TRUE(found_out);
}

TEST(NodeTest, TruncatedAndForeignMessagesAreDecodeErrors) {
  Node node(MemqOptions());
  int received = 0;
  node.Subscribe<cairn::lcmt_velocity_command>("r1.CMD_VEL",
                                               [&](const cairn::lcmt_velocity_command&) { ++received; });
  // Truncated: a valid encoding cut in half.
  cairn::lcmt_velocity_command cmd{};
  cmd.robot = "r1";
  std::vector<uint8_t> buf(cmd.getEncodedSize());
  cmd.encode(buf.data(), 0, static_cast<int>(buf.size()));
  node.lcm().publish("r1.CMD_VEL", buf.data(), static_cast<unsigned>(buf.size() / 2));
  // Foreign fingerprint: another type on this channel.
  cairn::lcmt_goal goal{};
  node.lcm().publish("r1.CMD_VEL", &goal);
  SpinFor(node, 5);
  EXPECT_EQ(received, 0);
  EXPECT_EQ(node.decode_errors(), 2);
  EXPECT_EQ(node.MakeHealth().decode_errors, 2);
  // The node still works.
  node.Publish("r1.CMD_VEL", cmd);
  SpinFor(node, 3);
  EXPECT_EQ(received, 1);
}

TEST(NodeTest, HandlerExceptionIsCountedNotPropagated) {
  Node node(MemqOptions());
  node.Subscribe<cairn::lcmt_velocity_command>(
      "X", [](const cairn::lcmt_velocity_command&) { throw std::runtime_error("boom"); });
  cairn::lcmt_velocity_command cmd{};
  node.Publish("X", cmd);
  SpinFor(node, 3);
  EXPECT_EQ(node.handler_errors(), 1);
  EXPECT_EQ(node.MakeHealth().handler_errors, 1);
}

TEST(NodeTest, CountersAppearInHealth) {
  Node node(MemqOptions());
  node.CountDropped("nan_points", 5);
  node.Count("clamped_commands");
  const auto h = node.MakeHealth();
  EXPECT_EQ(h.dropped_inputs, 5);
  ASSERT_EQ(h.num_counters, 2);
  EXPECT_EQ(node.counter("nan_points"), 5);
  EXPECT_EQ(node.counter("clamped_commands"), 1);
}

TEST(NodeTest, TimersRunAndStopEndsSpin) {
  Node node(MemqOptions());
  int ticks = 0;
  node.AddTimer(0.01, [&] {
    if (++ticks == 3) node.Stop();
  });
  EXPECT_EQ(node.Spin(), 0);
  EXPECT_EQ(ticks, 3);
}

TEST(WithReceiveBufferTest, OnlyUdpmUrlsWithoutOneGetIt) {
  EXPECT_EQ(WithReceiveBuffer("udpm://239.255.76.67:7667?ttl=0", 4096),
            "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4096");
  EXPECT_EQ(WithReceiveBuffer("udpm://239.255.76.67:7667", 4096),
            "udpm://239.255.76.67:7667?recv_buf_size=4096");
  EXPECT_EQ(WithReceiveBuffer("udpm://239.255.76.67:7667?recv_buf_size=100", 4096),
            "udpm://239.255.76.67:7667?recv_buf_size=100");
  EXPECT_EQ(WithReceiveBuffer("memq://", 4096), "memq://");
}

}  // namespace
}  // namespace cairn::runtime
