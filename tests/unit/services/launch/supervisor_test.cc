#include "services/launch/supervisor.h"

#include <signal.h>
#include <sys/wait.h>

#include <map>
#include <memory>
#include <set>

#include <gtest/gtest.h>

namespace cairn::launch {
namespace {

// A fake process table: tests decide when processes exit.
class FakeRunner : public ProcessRunner {
 public:
  pid_t Spawn(const ProcessSpec& spec, std::string* error) override {
    if (fail_spawn.count(spec.name)) {
      *error = "no such file";
      return -1;
    }
    const pid_t pid = next_pid++;
    alive[pid] = spec.name;
    spawned.push_back(spec.name);
    return pid;
  }
  void Signal(pid_t pid, int sig) override {
    signals.emplace_back(alive.count(pid) ? alive[pid] : "?", sig);
    if (sig == SIGKILL || exit_on_signal) Exit(pid, sig == SIGKILL ? 9 : 0, sig == SIGKILL);
  }
  std::optional<int> Poll(pid_t pid) override {
    auto it = exited.find(pid);
    if (it == exited.end()) return std::nullopt;
    const int status = it->second;
    exited.erase(it);
    return status;
  }
  void Exit(pid_t pid, int code, bool by_signal = false) {
    alive.erase(pid);
    exited[pid] = by_signal ? code : (code << 8);  // wait status encoding
  }
  pid_t GroupOf(pid_t pid) override {
    auto it = groups.find(pid);
    return it == groups.end() ? -1 : it->second;
  }
  pid_t PidOf(const std::string& name) const {
    for (const auto& [pid, n] : alive) {
      if (n == name) return pid;
    }
    return -1;
  }

  pid_t next_pid{100};
  bool exit_on_signal{true};
  std::map<pid_t, std::string> alive;
  std::map<pid_t, int> exited;
  std::vector<std::string> spawned;
  std::vector<std::pair<std::string, int>> signals;
  std::set<std::string> fail_spawn;
  std::map<pid_t, pid_t> groups;  ///< pid -> process group, for pids of grandchildren
};

GraphSpec TwoProcessGraph(RestartPolicy policy = RestartPolicy::kOnFailure, int max_restarts = 2) {
  GraphSpec g;
  g.name = "g";
  ProcessSpec a;
  a.name = "a";
  a.executable = "/bin/a";
  a.restart = policy;
  a.max_restarts = max_restarts;
  a.backoff_s = 1.0;
  ProcessSpec b = a;
  b.name = "b";
  b.executable = "/bin/b";
  b.depends_on = {"a"};
  g.processes = {a, b};
  return g;
}

class SupervisorTest : public ::testing::Test {
 protected:
  void Make(GraphSpec g) {
    dut_ = std::make_unique<Supervisor>(std::move(g), &runner_, [this](const std::string& e) {
      events_.push_back(e);
    });
  }
  const ProcStatus& St(const std::string& name) {
    for (const auto& s : dut_->statuses()) {
      if (s.name == name) return s;
    }
    throw std::out_of_range(name);
  }
  FakeRunner runner_;
  std::vector<std::string> events_;
  std::unique_ptr<Supervisor> dut_;
};

TEST_F(SupervisorTest, StartsInDependencyOrderAfterReadiness) {
  Make(TwoProcessGraph());
  dut_->Tick(0.0);
  EXPECT_EQ(runner_.spawned, std::vector<std::string>{"a"});
  EXPECT_EQ(St("a").state, ProcState::kStarting);
  dut_->Tick(1.0);
  EXPECT_EQ(runner_.spawned.size(), 1u);  // b waits for a to be ready
  dut_->OnHeartbeat(runner_.PidOf("a"), "a", "", true, 1.0);
  dut_->Tick(1.1);
  EXPECT_EQ(St("a").state, ProcState::kReady);
  dut_->Tick(1.2);
  EXPECT_EQ(runner_.spawned, (std::vector<std::string>{"a", "b"}));
  dut_->OnHeartbeat(runner_.PidOf("b"), "b", "", true, 1.2);
  dut_->Tick(1.3);
  EXPECT_TRUE(dut_->AllReady());
}

// Issue 20: a heartbeat counts only from the pid the supervisor started (or a process in its
// group, started by a wrapper script). One forged with the process's name and robot and
// another pid marked it ready before.
TEST_F(SupervisorTest, AForgedHeartbeatCannotMarkAProcessReady) {
  Make(TwoProcessGraph());
  dut_->Tick(0.0);
  EXPECT_FALSE(dut_->OnHeartbeat(4242, "a", "", true, 0.0));
  EXPECT_FALSE(dut_->OnHeartbeat(0, "a", "", true, 0.0));
  dut_->Tick(0.5);
  EXPECT_EQ(St("a").state, ProcState::kStarting);
  EXPECT_EQ(runner_.spawned.size(), 1u);
  // The wrapper's child, in the group of the pid started: it counts.
  runner_.groups[4343] = runner_.PidOf("a");
  EXPECT_TRUE(dut_->OnHeartbeat(4343, "real-a", "", true, 0.0));
  dut_->Tick(0.6);
  EXPECT_EQ(St("a").state, ProcState::kReady);
}

TEST_F(SupervisorTest, NotReadyHeartbeatDoesNotCount) {
  Make(TwoProcessGraph());
  dut_->Tick(0.0);
  dut_->OnHeartbeat(runner_.PidOf("a"), "a", "", false, 0.0);
  dut_->Tick(0.5);
  EXPECT_EQ(St("a").state, ProcState::kStarting);
}

TEST_F(SupervisorTest, ChannelRateReadiness) {
  GraphSpec g = TwoProcessGraph();
  g.processes[0].ready.heartbeat = false;
  g.processes[0].ready.channel = "r.POSE";
  g.processes[0].ready.min_rate_hz = 10.0;
  Make(g);
  dut_->Tick(0.0);
  dut_->SetChannelRate("r.POSE", 4.0);
  dut_->Tick(0.5);
  EXPECT_EQ(St("a").state, ProcState::kStarting);
  dut_->SetChannelRate("r.POSE", 12.0);
  dut_->Tick(0.6);
  EXPECT_EQ(St("a").state, ProcState::kReady);
}

TEST_F(SupervisorTest, RestartsWithBackoffThenFailsForGood) {
  Make(TwoProcessGraph(RestartPolicy::kOnFailure, 2));
  dut_->Tick(0.0);
  runner_.Exit(runner_.PidOf("a"), 3);
  dut_->Tick(1.0);
  EXPECT_EQ(St("a").state, ProcState::kBackoff);
  dut_->Tick(1.5);  // back-off 1 s not over yet
  EXPECT_EQ(runner_.spawned.size(), 1u);
  dut_->Tick(2.0);
  EXPECT_EQ(runner_.spawned.size(), 2u);
  EXPECT_EQ(St("a").restarts, 1);
  runner_.Exit(runner_.PidOf("a"), 3);
  dut_->Tick(2.1);
  dut_->Tick(3.0);  // back-off doubled to 2 s
  EXPECT_EQ(runner_.spawned.size(), 2u);
  dut_->Tick(4.2);
  EXPECT_EQ(St("a").restarts, 2);
  runner_.Exit(runner_.PidOf("a"), 3);
  dut_->Tick(4.3);
  EXPECT_EQ(St("a").state, ProcState::kFailed);
  ASSERT_TRUE(dut_->FatalFailure().has_value());
  EXPECT_NE(dut_->FatalFailure()->find("'a'"), std::string::npos);
  EXPECT_NE(dut_->FatalFailure()->find("exited 3"), std::string::npos);
}

TEST_F(SupervisorTest, CleanExitUnderOnFailureIsNotRestarted) {
  Make(TwoProcessGraph(RestartPolicy::kOnFailure));
  dut_->Tick(0.0);
  runner_.Exit(runner_.PidOf("a"), 0);
  dut_->Tick(0.1);
  dut_->Tick(5.0);
  EXPECT_EQ(St("a").state, ProcState::kExited);
  EXPECT_EQ(runner_.spawned.size(), 1u);
  EXPECT_FALSE(dut_->FatalFailure().has_value());
}

TEST_F(SupervisorTest, KilledBySignalIsRestartedUnderAlways) {
  Make(TwoProcessGraph(RestartPolicy::kAlways));
  dut_->Tick(0.0);
  runner_.Exit(runner_.PidOf("a"), SIGKILL, /*by_signal=*/true);
  dut_->Tick(0.1);
  EXPECT_EQ(St("a").last_exit, "killed by SIGKILL");
  dut_->Tick(1.2);
  EXPECT_EQ(St("a").restarts, 1);
  EXPECT_EQ(St("a").state, ProcState::kStarting);
}

TEST_F(SupervisorTest, SpawnFailureOfRequiredProcessIsFatal) {
  Make(TwoProcessGraph());
  runner_.fail_spawn.insert("a");
  dut_->Tick(0.0);
  EXPECT_EQ(St("a").state, ProcState::kFailed);
  EXPECT_TRUE(dut_->FatalFailure().has_value());
}

TEST_F(SupervisorTest, ReadinessTimeoutKillsTheProcess) {
  GraphSpec g = TwoProcessGraph();
  g.processes[0].ready.timeout_s = 2.0;
  Make(g);
  dut_->Tick(0.0);
  dut_->Tick(2.5);
  ASSERT_FALSE(runner_.signals.empty());
  EXPECT_EQ(runner_.signals.back(), std::make_pair(std::string("a"), SIGKILL));
}

TEST_F(SupervisorTest, StopsInReverseOrderAndEscalates) {
  Make(TwoProcessGraph());
  dut_->Tick(0.0);
  dut_->OnHeartbeat(runner_.PidOf("a"), "a", "", true, 0.0);
  dut_->Tick(0.1);
  dut_->Tick(0.2);
  ASSERT_EQ(runner_.spawned.size(), 2u);
  runner_.exit_on_signal = false;  // b ignores SIGTERM
  dut_->RequestStop(1.0);
  dut_->Tick(1.0);
  ASSERT_EQ(runner_.signals.size(), 1u);
  EXPECT_EQ(runner_.signals[0], std::make_pair(std::string("b"), SIGTERM));  // a waits for b
  dut_->Tick(7.0);  // grace 5 s passed
  EXPECT_EQ(runner_.signals.back(), std::make_pair(std::string("b"), SIGKILL));
  runner_.exit_on_signal = true;
  dut_->Tick(7.1);  // b's exit is collected; a is signalled now
  EXPECT_EQ(runner_.signals.back(), std::make_pair(std::string("a"), SIGTERM));
  dut_->Tick(7.2);
  EXPECT_TRUE(dut_->AllDown());
  EXPECT_FALSE(dut_->FatalFailure().has_value());
}

// Starts the two-process graph and makes both ready (a at 0.1, b at 0.3).
void StartBothReady(Supervisor& dut, FakeRunner& runner) {
  dut.Tick(0.0);
  dut.OnHeartbeat(runner.PidOf("a"), "a", "", true, 0.05);
  dut.Tick(0.1);
  dut.Tick(0.2);
  dut.OnHeartbeat(runner.PidOf("b"), "b", "", true, 0.25);
  dut.Tick(0.3);
  ASSERT_TRUE(dut.AllReady());
}

// Issue 20: a process that stops heartbeating after it was ready (hung, stopped) was left alone
// for ever. Now it is sent its stop signal after liveness_timeout_s, SIGKILL after its grace
// period, and restarted; heartbeats from another pid, forged with its name, do not keep it alive.
TEST_F(SupervisorTest, AProcessThatStopsHeartbeatingAfterReadyIsRestarted) {
  GraphSpec g = TwoProcessGraph();
  g.processes[1].liveness_timeout_s = 3.0;
  g.processes[1].grace_s = 1.0;
  Make(g);
  StartBothReady(*dut_, runner_);
  const pid_t b = runner_.PidOf("b");
  runner_.exit_on_signal = false;  // hung: it ignores SIGTERM too
  for (double t = 0.5; t <= 3.0; t += 0.5) {
    dut_->OnHeartbeat(runner_.PidOf("a"), "a", "", true, t);
    EXPECT_FALSE(dut_->OnHeartbeat(9999, "b", "", true, t));  // forged
    dut_->Tick(t);
  }
  EXPECT_EQ(St("b").state, ProcState::kReady);  // 2.75 s of silence: within the timeout
  EXPECT_TRUE(runner_.signals.empty());
  dut_->Tick(3.4);
  EXPECT_EQ(St("b").state, ProcState::kStopping);
  ASSERT_EQ(runner_.signals.size(), 1u);
  EXPECT_EQ(runner_.signals[0], std::make_pair(std::string("b"), SIGTERM));
  EXPECT_EQ(St("a").state, ProcState::kReady);  // a kept heartbeating
  dut_->Tick(4.0);
  EXPECT_EQ(runner_.signals.size(), 1u);
  runner_.exit_on_signal = true;
  dut_->Tick(4.5);  // grace 1 s over: SIGKILL, and the exit is collected next tick
  EXPECT_EQ(runner_.signals.back(), std::make_pair(std::string("b"), SIGKILL));
  dut_->Tick(4.6);
  EXPECT_EQ(St("b").state, ProcState::kBackoff);
  EXPECT_NE(St("b").last_exit.find("hung (no heartbeat for 3 s)"), std::string::npos)
      << St("b").last_exit;
  dut_->Tick(5.7);
  EXPECT_EQ(St("b").state, ProcState::kStarting);
  EXPECT_NE(runner_.PidOf("b"), b);
  EXPECT_EQ(St("b").restarts, 1);
  EXPECT_FALSE(dut_->FatalFailure().has_value());
}

TEST_F(SupervisorTest, AHungProcessUnderRestartNeverFailsTheGraph) {
  GraphSpec g = TwoProcessGraph(RestartPolicy::kNever);
  g.processes[1].liveness_timeout_s = 2.0;
  Make(g);
  StartBothReady(*dut_, runner_);
  for (double t = 0.5; t <= 2.5; t += 0.5) {
    dut_->OnHeartbeat(runner_.PidOf("a"), "a", "", true, t);
    dut_->Tick(t);
  }
  dut_->Tick(2.6);  // stopped at 2.5 (the fake exits on SIGTERM); the exit is collected here
  dut_->Tick(2.7);
  EXPECT_EQ(St("b").state, ProcState::kFailed);
  ASSERT_TRUE(dut_->FatalFailure().has_value());
  EXPECT_NE(dut_->FatalFailure()->find("hung"), std::string::npos) << *dut_->FatalFailure();
}

TEST_F(SupervisorTest, LivenessOfAChannelReadinessIsItsRate) {
  GraphSpec g = TwoProcessGraph();
  g.processes[0].ready.heartbeat = false;
  g.processes[0].ready.channel = "r.POSE";
  g.processes[0].ready.min_rate_hz = 10.0;
  g.processes[0].liveness_timeout_s = 2.0;
  g.processes[1].liveness_timeout_s = 0.0;  // off: b never heartbeats after ready
  Make(g);
  dut_->Tick(0.0);
  dut_->SetChannelRate("r.POSE", 50.0);
  dut_->Tick(0.1);
  ASSERT_EQ(St("a").state, ProcState::kReady);
  dut_->OnHeartbeat(runner_.PidOf("b"), "b", "", true, 0.15);
  dut_->Tick(0.2);
  dut_->Tick(1.0);
  dut_->SetChannelRate("r.POSE", 3.0);  // too slow from 1.0 on
  dut_->Tick(2.0);
  dut_->Tick(3.0);
  EXPECT_EQ(St("a").state, ProcState::kReady);
  dut_->Tick(3.1);
  EXPECT_EQ(St("a").state, ProcState::kStopping);
  EXPECT_EQ(St("b").state, ProcState::kReady);  // 20 s without a heartbeat, liveness off
  dut_->Tick(20.0);
  EXPECT_EQ(St("b").state, ProcState::kReady);
}

// Issue 20: the restart counter never reset, so a process that failed max_restarts times over
// days failed the graph for good. After reset_restarts_after_s of being ready, the back-off
// starts again from backoff_s and max_restarts counts afresh; status still counts every restart.
TEST_F(SupervisorTest, TheRestartCountResetsAfterAStablePeriod) {
  GraphSpec g = TwoProcessGraph(RestartPolicy::kOnFailure, /*max_restarts=*/1);
  g.processes[0].reset_restarts_after_s = 10.0;
  g.processes[0].liveness_timeout_s = 0.0;
  g.processes[1].liveness_timeout_s = 0.0;
  Make(g);
  StartBothReady(*dut_, runner_);
  runner_.Exit(runner_.PidOf("a"), 3);
  dut_->Tick(1.0);
  dut_->Tick(2.0);  // back-off 1 s
  ASSERT_EQ(St("a").restarts, 1);
  dut_->OnHeartbeat(runner_.PidOf("a"), "a", "", true, 2.05);
  dut_->Tick(2.1);
  ASSERT_EQ(St("a").state, ProcState::kReady);
  dut_->Tick(12.0);  // ready 9.9 s: not yet
  EXPECT_EQ(St("a").recent_restarts, 1);
  dut_->Tick(12.2);
  EXPECT_EQ(St("a").recent_restarts, 0);
  EXPECT_NE(events_.back().find("reset"), std::string::npos) << events_.back();
  // Failing again restarts it after backoff_s (not 2 s), and does not exceed max_restarts.
  runner_.Exit(runner_.PidOf("a"), 3);
  dut_->Tick(13.0);
  EXPECT_EQ(St("a").state, ProcState::kBackoff);
  dut_->Tick(14.0);
  EXPECT_EQ(St("a").state, ProcState::kStarting);
  EXPECT_EQ(St("a").restarts, 2);
  EXPECT_FALSE(dut_->FatalFailure().has_value());
  // Without a stable period in between, the next failure is one too many.
  runner_.Exit(runner_.PidOf("a"), 3);
  dut_->Tick(14.5);
  EXPECT_EQ(St("a").state, ProcState::kFailed);
  EXPECT_TRUE(dut_->FatalFailure().has_value());
}

}  // namespace
}  // namespace cairn::launch
