// cairn-launch's inputs: LaunchService over a supervisor of a two-process graph (one ready by
// heartbeat, one by a channel's rate) on memq://, fed heartbeats and metered traffic through the
// node's decode and the real handler. The processes are a fake table (pids 1000 and up), so the
// fuzzer can name them in forged heartbeats; nothing is spawned.

#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "services/launch/graph.h"
#include "services/launch/lcm/launch_service.h"
#include "services/launch/supervisor.h"
#include "tests/fuzz/bus_channels.h"
#include "tests/fuzz/bus_feed.h"
#include "tests/support/memq_node.h"

namespace {

class FakeRunner : public cairn::launch::ProcessRunner {
 public:
  pid_t Spawn(const cairn::launch::ProcessSpec&, std::string*) override { return next_pid_++; }
  void Signal(pid_t pid, int signal) override {
    if (signal == SIGKILL || signal == SIGTERM) exited_[pid] = signal;
  }
  std::optional<int> Poll(pid_t pid) override {
    auto it = exited_.find(pid);
    if (it == exited_.end()) return std::nullopt;
    const int status = it->second;
    exited_.erase(it);
    return status;
  }

 private:
  pid_t next_pid_{1000};
  std::map<pid_t, int> exited_;
};

cairn::launch::GraphSpec Graph() {
  cairn::launch::GraphSpec g;
  g.name = "fuzz";
  cairn::launch::ProcessSpec a;
  a.name = "a";
  a.executable = "/bin/true";
  a.liveness_timeout_s = 0.05;
  a.grace_s = 0.01;
  a.backoff_s = 0.0;
  a.max_backoff_s = 0.0;
  a.max_restarts = 1000000;
  cairn::launch::ProcessSpec b = a;
  b.name = "b";
  b.depends_on = {"a"};
  b.ready.heartbeat = false;
  b.ready.channel = cairn::channels::ForRobot(cairn::fuzz::kRobot, cairn::channels::kPose);
  b.ready.min_rate_hz = 10.0;
  g.processes = {a, b};
  return g;
}

std::string StatusPath() {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("cairn_fuzz_launcher_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  return (dir / "status.json").string();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::vector<std::string> channels = cairn::fuzz::LauncherChannels();
  static const std::string status_path = StatusPath();
  cairn::runtime::Node node(cairn::testing::MemqNodeOptions("cairn-launch"));
  FakeRunner runner;
  cairn::launch::Supervisor supervisor(Graph(), &runner, [](const std::string&) {});
  cairn::launch::LaunchService service(&node, &supervisor, &runner, status_path);
  // The supervisor's clock is the service's (steady); its timer ticks it every 0.1 s, too
  // seldom within one input, so it is ticked after every message as well: the first tick
  // "starts" a (pid 1000), a heartbeat from 1000 makes it ready and b (1001) starts.
  auto now = [] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
  };
  supervisor.Tick(now());
  cairn::fuzz::FeedBus(node, channels, data, size, [&] { supervisor.Tick(now()); });
  supervisor.Tick(now() + 1.0);  // a second later: liveness and restarts
  (void)service.MakeStatus(now());
  return 0;
}
