#include "services/launch/graph.h"

#include <signal.h>

#include <gtest/gtest.h>

namespace cairn::launch {
namespace {

// /bin/true exists on every Debian machine.
constexpr char kGood[] = R"(
name: two
processes:
  first:
    command: /bin/true
    robot: rover1
    ready: {channel: rover1.POSE, min_rate_hz: 10}
    restart: always
    max_restarts: 3
    stop_signal: SIGINT
    expected_rates_hz: {rover1.POSE: 50}
  second:
    command: true
    args: [--x, "1"]
    env: {A: b}
    depends_on: [first]
)";

TEST(GraphTest, LoadsAndOrders) {
  const GraphSpec g = LoadGraphString(kGood, "g.yaml", {"/nonexistent", "/bin"});
  ASSERT_EQ(g.processes.size(), 2u);
  EXPECT_EQ(g.name, "two");
  EXPECT_EQ(g.run_dir, "var/run/two");
  const ProcessSpec* first = g.Find("first");
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(first->restart, RestartPolicy::kAlways);
  EXPECT_EQ(first->stop_signal, SIGINT);
  EXPECT_FALSE(first->ready.heartbeat);  // a channel readiness replaces the heartbeat default
  EXPECT_EQ(first->ready.channel, "rover1.POSE");
  EXPECT_EQ(g.Find("second")->executable.substr(g.Find("second")->executable.size() - 5), "/true");
  EXPECT_EQ(g.Find("second")->env.at("A"), "b");
  EXPECT_EQ(g.StartOrder(), (std::vector<std::string>{"first", "second"}));
  EXPECT_DOUBLE_EQ(g.ExpectedRates().at("rover1.POSE"), 50.0);
}

TEST(GraphTest, LivenessRestartResetAndLogRotationKeys) {
  const GraphSpec defaults = LoadGraphString(kGood, "g.yaml", {"/bin"});
  EXPECT_DOUBLE_EQ(defaults.log_max_mb, 16.0);
  EXPECT_EQ(defaults.log_keep, 3);
  EXPECT_DOUBLE_EQ(defaults.Find("first")->liveness_timeout_s, 10.0);
  EXPECT_DOUBLE_EQ(defaults.Find("first")->reset_restarts_after_s, 60.0);
  const GraphSpec g = LoadGraphString(
      "log_max_mb: 0.5\nlog_keep: 5\nprocesses:\n  a:\n    command: /bin/true\n"
      "    liveness_timeout_s: 0\n    reset_restarts_after_s: 30\n",
      "g.yaml", {});
  EXPECT_DOUBLE_EQ(g.log_max_mb, 0.5);
  EXPECT_EQ(g.log_keep, 5);
  EXPECT_DOUBLE_EQ(g.processes[0].liveness_timeout_s, 0.0);
  EXPECT_DOUBLE_EQ(g.processes[0].reset_restarts_after_s, 30.0);
}

void ExpectError(const std::string& yaml, const std::string& fragment) {
  try {
    LoadGraphString(yaml, "bad.yaml", {});
    FAIL() << "expected an error containing " << fragment;
  } catch (const common::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(GraphTest, RefusesUnknownKeyWithLine) {
  ExpectError("processes:\n  a:\n    command: /bin/true\n    comand: x\n", "bad.yaml:4: unknown key 'processes.a.comand'");
}

TEST(GraphTest, RefusesCycles) {
  ExpectError(
      "processes:\n  a:\n    command: /bin/true\n    depends_on: [c]\n  b:\n    command: /bin/true\n"
      "    depends_on: [a]\n  c:\n    command: /bin/true\n    depends_on: [b]\n",
      "dependency cycle: a -> c -> b -> a");
}

TEST(GraphTest, RefusesMissingExecutableAndUnknownDependency) {
  ExpectError("processes:\n  a:\n    command: no-such-program-xyz\n", "bad.yaml:3: process 'a': executable 'no-such-program-xyz' not found");
  ExpectError("processes:\n  a:\n    command: /bin/true\n    depends_on: [zz]\n", "depends on unknown process 'zz'");
  ExpectError("processes:\n  a:\n    command: /bin/true\n    restart: sometimes\n", "restart must be");
  ExpectError("processes:\n  a:\n    command: /bin/true\n    stop_signal: SIGFOO\n", "unknown signal");
  ExpectError("processes: {}\n", "no processes");
  ExpectError("processes:\n  a:\n    command: /bin/true\n    liveness_timeout_s: -1\n",
              "liveness_timeout_s and reset_restarts_after_s must be >= 0");
  ExpectError("processes:\n  a:\n    command: /bin/true\n    reset_restarts_after_s: .nan\n",
              "liveness_timeout_s and reset_restarts_after_s must be >= 0");
  ExpectError("log_keep: 0\nprocesses:\n  a:\n    command: /bin/true\n", "bad.yaml:1: log_max_mb");
  ExpectError("log_max_mb: -2\nprocesses:\n  a:\n    command: /bin/true\n", "bad.yaml:1: log_max_mb");
  // Without executable checks (cairn-spy reading expected rates) a missing program is fine.
  EXPECT_NO_THROW(LoadGraphString("processes:\n  a:\n    command: no-such-program-xyz\n", "x", {}, false));
}

TEST(GraphTest, ParsesSignals) {
  EXPECT_EQ(ParseSignal("SIGTERM"), SIGTERM);
  EXPECT_EQ(ParseSignal("INT"), SIGINT);
  EXPECT_EQ(ParseSignal("9"), 9);
  EXPECT_THROW(ParseSignal("nope"), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::launch
