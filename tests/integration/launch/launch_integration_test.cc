// cairn-launch against real processes on a private bus.

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <errno.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include "cairn/lcmt_health.hpp"

#include "cairn/lcmtypes_registry.hpp"
#include "services/launch/status.h"
#include "tests/support/harness.h"

namespace cairn::testing {
namespace {

// Keys added to the pair graph: at its top, to the watcher, to the follower (YAML lines).
struct PairExtras {
  std::string top;
  std::string watcher_refresh_s{"10"};
  std::string follower;
};

std::string WriteGraph(const std::string& dir, const std::string& url,
                       const PairExtras& extras = {}) {
  const std::string path = dir + "/pair.yaml";
  std::ofstream out(path);
  out << "name: pair\n"
         "lcm_url: "
      << url << "\n"
      << extras.top
      << "processes:\n"
         "  watcher:\n"
         "    command: "
      << BinPath("cairn-spy")
      << "\n"
         "    args: [--refresh, '"
      << extras.watcher_refresh_s
      << "']\n"
         "    restart: always\n"
         "    backoff_s: 0.2\n"
         "  follower:\n"
         "    command: "
      << BinPath("cairn-spy")
      << "\n"
         "    args: [--refresh, '10']\n"
         "    depends_on: [watcher]\n"
         "    restart: on-failure\n"
         "    backoff_s: 0.2\n"
         "    expected_rates_hz: {HEALTH: 2.0}\n"
      << extras.follower;
  return path;
}

std::optional<launch::GraphStatus> ReadStatus(const std::string& run_dir) {
  std::string error;
  return launch::ReadStatusFile(run_dir + "/status.json", &error);
}

// Running: a pid that exists and is not a zombie (an orphan's zombie waits for a reaper that
// may be slow, or absent, in a container).
bool Running(int pid) {
  if (kill(pid, 0) != 0) return false;
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string content;
  std::getline(stat, content);
  const auto paren = content.rfind(')');
  return paren == std::string::npos || paren + 2 >= content.size() || content[paren + 2] != 'Z';
}

const launch::ProcessRow* Row(const launch::GraphStatus& s, const std::string& name) {
  return launch::FindProcess(s, name);
}

// The pair graph under `cairn-launch up` on the test's bus, and its status once ready.
struct PairGraph {
  ChildProcess* launcher{nullptr};
  std::string run_dir;
  std::optional<launch::GraphStatus> status;
};

// Starts the pair graph and waits (30 s at most) until both processes are ready.
bool StartPairGraph(ProcessSet& procs, PairGraph* g, const PairExtras& extras = {}) {
  const std::string graph = WriteGraph(procs.dir(), procs.url(), extras);
  g->run_dir = procs.dir() + "/run";
  g->launcher = &procs.StartRaw("cairn-launch",
                                {BinPath("cairn-launch"), "up", graph, "--run-dir", g->run_dir});
  return WaitFor(
      [&] {
        g->status = ReadStatus(g->run_dir);
        return g->status && g->status->state == "ready";
      },
      30.0);
}

TEST(LaunchIntegrationTest, RestartsAKilledProcessAndReportsStatus) {
  ProcessSet procs(PrivateLcmUrl());
  // Ready means both processes sent READY heartbeats.
  PairGraph g;
  ASSERT_TRUE(StartPairGraph(procs, &g)) << "graph never became ready";
  ChildProcess& launcher = *g.launcher;
  const std::string& run_dir = g.run_dir;
  std::optional<launch::GraphStatus> status = g.status;
  const launch::ProcessRow* follower = Row(*status, "follower");
  ASSERT_NE(follower, nullptr);
  const int old_pid = follower->pid;
  ASSERT_GT(old_pid, 0);
  EXPECT_EQ(follower->restarts, 0);

  // SIGKILL one process: the launcher restarts it.
  ASSERT_EQ(kill(old_pid, SIGKILL), 0);
  ASSERT_TRUE(WaitFor(
      [&] {
        status = ReadStatus(run_dir);
        if (!status) return false;
        const auto* row = Row(*status, "follower");
        return row && row->restarts == 1 && row->pid > 0 && row->pid != old_pid &&
               row->state == "ready";
      },
      30.0))
      << "follower was not restarted";
  EXPECT_EQ(Row(*status, "follower")->last_exit, "killed by SIGKILL");

  // `cairn-launch status` prints the table with the restart count.
  ChildProcess& status_cmd =
      procs.StartRaw("status", {BinPath("cairn-launch"), "status", "--run-dir", run_dir});
  auto exit = status_cmd.WaitExit(20.0);
  ASSERT_TRUE(exit.has_value());
  EXPECT_EQ(*exit, 0);
  const std::string table = status_cmd.Log();
  EXPECT_TRUE(std::regex_search(table, std::regex(R"(follower\s+-\s+ready\s+\d+\s+1\s)"))) << table;
  EXPECT_TRUE(std::regex_search(table, std::regex(R"(watcher\s+-\s+ready\s+\d+\s+0\s)"))) << table;

  // `down` stops everything and the launcher exits 0: the processes themselves are gone, not only
  // the launcher's record of them.
  status = ReadStatus(run_dir);
  ASSERT_TRUE(status.has_value());
  std::vector<int> pids;
  for (const auto& p : status->processes) {
    ASSERT_GT(p.pid, 0) << p.name;
    pids.push_back(p.pid);
  }
  ASSERT_EQ(pids.size(), 2u);
  ChildProcess& down =
      procs.StartRaw("down", {BinPath("cairn-launch"), "down", "--run-dir", run_dir});
  ASSERT_TRUE(down.WaitExit(30.0).has_value());
  auto launcher_exit = launcher.WaitExit(30.0);
  ASSERT_TRUE(launcher_exit.has_value());
  EXPECT_TRUE(WIFEXITED(*launcher_exit) && WEXITSTATUS(*launcher_exit) == 0);
  status = ReadStatus(run_dir);
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(status->state, "stopped");
  for (const auto& p : status->processes) EXPECT_EQ(p.pid, -1) << p.name;
  for (int pid : pids) {
    EXPECT_TRUE(WaitFor([&] { return kill(pid, 0) == -1 && errno == ESRCH; }, 10.0))
        << "process " << pid << " outlived `cairn-launch down`";
  }
}

// Issue 20: the launcher killed outright (SIGKILL: no chance to stop anything) takes its
// children with it; they outlived it before.
TEST(LaunchIntegrationTest, AKilledLauncherTakesItsChildrenWithIt) {
  ProcessSet procs(PrivateLcmUrl());
  PairGraph g;
  ASSERT_TRUE(StartPairGraph(procs, &g)) << "graph never became ready";
  ChildProcess& launcher = *g.launcher;
  std::vector<int> pids;
  for (const auto& p : g.status->processes) {
    ASSERT_GT(p.pid, 0) << p.name;
    pids.push_back(p.pid);
  }
  launcher.Signal(SIGKILL);
  ASSERT_TRUE(launcher.WaitExit(10.0).has_value());
  for (int pid : pids) {
    EXPECT_TRUE(WaitFor([&] { return !Running(pid); }, 10.0))
        << "process " << pid << " outlived its launcher";
  }
}

// Resident memory of a process (MB), from /proc; -1 when gone.
double RssMb(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return -1.0;
}

// `cairn-launch status` answers (exit 0) within a second; then `down` stops the graph.
void ExpectStatusWithinASecondThenDown(ProcessSet& procs, const std::string& run_dir) {
  const auto asked = std::chrono::steady_clock::now();
  ChildProcess& status_cmd =
      procs.StartRaw("status", {BinPath("cairn-launch"), "status", "--run-dir", run_dir});
  auto exit = status_cmd.WaitExit(5.0);
  ASSERT_TRUE(exit.has_value());
  EXPECT_EQ(*exit, 0);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - asked).count(), 1.0);
  ChildProcess& down =
      procs.StartRaw("down", {BinPath("cairn-launch"), "down", "--run-dir", run_dir});
  ASSERT_TRUE(down.WaitExit(40.0).has_value());
}

// Issue 20: a process that stopped heartbeating after it was ready (here: stopped with
// SIGSTOP, as a deadlock or a wait on a dead peer would leave it) was left alone for ever, and
// the restart count never reset. Now the hung process is stopped (SIGTERM, SIGKILL after its
// grace period) and restarted; once it has been ready for reset_restarts_after_s its count
// towards max_restarts is reset, so a second failure (max_restarts: 1) is restarted too.
TEST(LaunchIntegrationTest, AHungProcessIsRestartedAndAStableOneEarnsItsRestartsBack) {
  ProcessSet procs(PrivateLcmUrl());
  PairExtras extras;
  extras.follower =
      "    liveness_timeout_s: 2\n"
      "    grace_s: 1\n"
      "    max_restarts: 1\n"
      "    reset_restarts_after_s: 2\n";
  PairGraph g;
  ASSERT_TRUE(StartPairGraph(procs, &g, extras)) << "graph never became ready";
  const int hung_pid = Row(*g.status, "follower")->pid;
  ASSERT_GT(hung_pid, 0);
  ASSERT_EQ(kill(hung_pid, SIGSTOP), 0);
  std::optional<launch::GraphStatus> status;
  int restarted_pid = -1;
  ASSERT_TRUE(WaitFor(
      [&] {
        status = ReadStatus(g.run_dir);
        const auto* row = status ? Row(*status, "follower") : nullptr;
        if (!row || row->restarts != 1 || row->state != "ready" || row->pid == hung_pid) {
          return false;
        }
        restarted_pid = row->pid;
        return true;
      },
      30.0))
      << "the hung follower was not restarted\n"
      << g.launcher->Log();
  EXPECT_NE(Row(*status, "follower")->last_exit.find("hung (no heartbeat for 2 s)"),
            std::string::npos)
      << Row(*status, "follower")->last_exit;
  EXPECT_TRUE(WaitFor([&] { return !Running(hung_pid); }, 10.0)) << "the hung process lives on";
  EXPECT_EQ(Row(*status, "watcher")->restarts, 0);  // the other process was left alone

  // Stable for 2 s: the count towards max_restarts is reset (the launcher says so).
  ASSERT_TRUE(WaitFor(
      [&] {
        return g.launcher->Log().find("'follower' ready for 2 s; its back-off and restart count") !=
               std::string::npos;
      },
      20.0))
      << g.launcher->Log();
  ASSERT_EQ(kill(restarted_pid, SIGKILL), 0);
  ASSERT_TRUE(WaitFor(
      [&] {
        status = ReadStatus(g.run_dir);
        const auto* row = status ? Row(*status, "follower") : nullptr;
        return row && row->restarts == 2 && row->state == "ready" && row->pid != restarted_pid;
      },
      30.0))
      << "a second failure after a stable period was not restarted\n"
      << g.launcher->Log();
  EXPECT_EQ(status->state, "ready");
  ExpectStatusWithinASecondThenDown(procs, g.run_dir);
}

// Issue 20: the processes' logs grew without limit. With log_max_mb 0.01 and log_keep 2, a
// process writing about 20 KB a second has its log rotated every second or so: two copies kept,
// none older, each near the limit, and the process (not restarted) keeps writing to its log.
TEST(LaunchIntegrationTest, LogsRotateAtTheirSizeLimit) {
  ProcessSet procs(PrivateLcmUrl());
  PairExtras extras;
  extras.top = "log_max_mb: 0.01\nlog_keep: 2\n";
  extras.watcher_refresh_s = "0.02";  // a table 50 times a second
  PairGraph g;
  ASSERT_TRUE(StartPairGraph(procs, &g, extras)) << "graph never became ready";
  const int watcher_pid = Row(*g.status, "watcher")->pid;
  const std::string log = g.run_dir + "/logs/watcher.log";
  auto rotations = [&] {
    const std::string text = g.launcher->Log();
    int n = 0;
    for (auto at = text.find("rotated the log of 'watcher'"); at != std::string::npos;
         at = text.find("rotated the log of 'watcher'", at + 1)) {
      ++n;
    }
    return n;
  };
  ASSERT_TRUE(WaitFor([&] { return rotations() >= 3; }, 30.0)) << g.launcher->Log();
  namespace fs = std::filesystem;
  EXPECT_TRUE(fs::exists(log + ".1"));
  EXPECT_TRUE(fs::exists(log + ".2"));
  EXPECT_FALSE(fs::exists(log + ".3"));
  // A copy holds what passed the limit in the second between checks: far below unbounded.
  EXPECT_GT(fs::file_size(log + ".1"), 10u * 1024u);
  EXPECT_LT(fs::file_size(log + ".1"), 200u * 1024u);
  std::ifstream copy(log + ".1");
  std::stringstream copied;
  copied << copy.rdbuf();
  EXPECT_NE(copied.str().find("cairn-spy on"), std::string::npos);  // the process's own output
  const auto size_before = fs::file_size(log);
  EXPECT_TRUE(WaitFor([&] { return fs::file_size(log) != size_before; }, 10.0))
      << "the process stopped writing to its log";
  const auto status = ReadStatus(g.run_dir);
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(Row(*status, "watcher")->pid, watcher_pid);
  EXPECT_EQ(Row(*status, "watcher")->restarts, 0);
  EXPECT_TRUE(fs::exists(g.run_dir + "/logs/follower.log"));
  EXPECT_FALSE(fs::exists(g.run_dir + "/logs/follower.log.1"));  // small: never rotated
  ExpectStatusWithinASecondThenDown(procs, g.run_dir);
}

// Issue 20's finding: one 84-byte heartbeat whose num_channels says 67 million made the
// launcher grow by 220 MB a second and stop answering. Now a hundred of them change nothing:
// the launcher and the two spies (which decode every type) stay within 50 MB of what they
// held, the launcher keeps writing its status, and `status` answers within 1 s.
TEST(LaunchIntegrationTest, AHeartbeatBombChangesNothing) {
  ProcessSet procs(PrivateLcmUrl());
  PairGraph g;
  ASSERT_TRUE(StartPairGraph(procs, &g)) << "graph never became ready";
  ChildProcess& launcher = *g.launcher;
  const std::string& run_dir = g.run_dir;
  std::optional<launch::GraphStatus> status = g.status;
  std::vector<int> pids = {launcher.pid()};
  for (const auto& p : status->processes) pids.push_back(p.pid);
  std::vector<double> rss_before;
  for (int pid : pids) rss_before.push_back(RssMb(pid));

  lcm::LCM bus(procs.url());
  ASSERT_TRUE(bus.good());
  cairn::lcmt_health h{};
  std::vector<uint8_t> bomb(h.getEncodedSize());
  ASSERT_EQ(h.encode(bomb.data(), 0, static_cast<int>(bomb.size())), 84);
  const size_t num_channels_at = 8 + 8 + 8 + 5 + 5 + 4 + 1 + 8 + 8 + 8 + 8 + 5;
  bomb[num_channels_at] = 0x04;  // 0x04000000 = 67,108,864
  for (int k = 0; k < 100; ++k) {
    bus.publish("HEALTH", bomb.data(), static_cast<unsigned>(bomb.size()));
  }
  WaitFor([] { return false; }, 2.0);
  for (size_t i = 0; i < pids.size(); ++i) {
    const double rss = RssMb(pids[i]);
    ASSERT_GT(rss, 0.0) << "process " << pids[i] << " died";
    EXPECT_LT(rss - rss_before[i], 50.0)
        << "process " << pids[i] << " grew from " << rss_before[i] << " MB to " << rss << " MB";
  }
  // The launcher's loop still runs: it rewrites its status file.
  namespace fs = std::filesystem;
  const auto written = fs::last_write_time(run_dir + "/status.json");
  EXPECT_TRUE(WaitFor(
      [&] {
        std::error_code ec;
        return fs::last_write_time(run_dir + "/status.json", ec) != written;
      },
      3.0))
      << "the launcher stopped writing its status";
  ExpectStatusWithinASecondThenDown(procs, run_dir);
}

// Every message of every variable-size type whose count or length word claims 67 million:
// the type's empty encoding with one 4-byte word after the fingerprint set so, for each word
// that makes the bounded decoder refuse it (a count or a length; others decode as a value).
std::vector<std::vector<uint8_t>> BombsOfEveryType() {
  std::vector<std::vector<uint8_t>> bombs;
  for (const cairn::LcmTypeInfo& type : cairn::AllLcmTypes()) {
    const std::vector<uint8_t> sample = type.sample();
    for (size_t at = 8; at + 4 <= sample.size(); ++at) {
      std::vector<uint8_t> bytes = sample;
      bytes[at] = 0x04;  // 0x04000000 = 67,108,864
      bytes[at + 1] = bytes[at + 2] = bytes[at + 3] = 0;
      if (type.decode(bytes.data(), static_cast<int>(bytes.size())) < 0) bombs.push_back(bytes);
    }
  }
  return bombs;
}

// Messages a second on a channel, counted by a listener on its own thread.
class RateMeter {
 public:
  explicit RateMeter(const std::string& url) : lcm_(url) {
    lcm_.subscribe(".*", &RateMeter::On, this);
    thread_ = std::thread([this] {
      while (!stop_) lcm_.handleTimeout(50);
    });
  }
  ~RateMeter() {
    stop_ = true;
    thread_.join();
  }
  std::map<std::string, double> Measure(double seconds) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      counts_.clear();
    }
    WaitFor([] { return false; }, seconds);
    std::lock_guard<std::mutex> lock(mutex_);
    std::map<std::string, double> rates;
    for (const auto& [channel, n] : counts_) rates[channel] = n / seconds;
    return rates;
  }

 private:
  void On(const lcm::ReceiveBuffer*, const std::string& channel) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++counts_[channel];
  }
  lcm::LCM lcm_;
  std::mutex mutex_;
  std::map<std::string, int64_t> counts_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Issue 20's acceptance: the demo graph (simulator, mapper, navigator, map store under
// cairn-launch) takes the 67-million-count bomb of every variable-size type on every channel
// its processes read. Every process stays within 50 MB of what it held and keeps its rates, and
// `cairn-launch status` answers within 1 s.
TEST(LaunchIntegrationTest, TheDemoGraphTakesABombOfEveryTypeOnEveryChannel) {
  ProcessSet procs(PrivateLcmUrl());
  std::string yaml;
  {
    std::ifstream in(SourcePath("config/graphs/demo.yaml"));
    std::stringstream text;
    text << in.rdbuf();
    yaml = text.str();
  }
  yaml = std::regex_replace(yaml, std::regex("var/cairn\\.db"), procs.dir() + "/cairn.db");
  yaml = std::regex_replace(yaml, std::regex("\\bconfig/"), SourcePath("config") + "/");
  yaml = "lcm_url: " + procs.url() + "\n" + yaml;
  const std::string graph = procs.dir() + "/demo.yaml";
  std::ofstream(graph) << yaml;
  const std::string run_dir = procs.dir() + "/run";
  procs.StartRaw("cairn-launch", {BinPath("cairn-launch"), "up", graph, "--run-dir", run_dir});
  std::optional<launch::GraphStatus> status;
  ASSERT_TRUE(WaitFor(
      [&] {
        status = ReadStatus(run_dir);
        return status && status->state == "ready";
      },
      90.0))
      << "the demo graph never became ready";
  std::vector<int> pids;
  std::vector<std::string> names;
  for (const auto& p : status->processes) {
    pids.push_back(p.pid);
    names.push_back(p.name);
  }
  RateMeter meter(procs.url());
  WaitFor([] { return false; }, 3.0);  // the mapper's first maps
  std::vector<double> rss_before;
  for (int pid : pids) rss_before.push_back(RssMb(pid));
  const std::map<std::string, double> before = meter.Measure(3.0);

  const std::vector<std::vector<uint8_t>> bombs = BombsOfEveryType();
  ASSERT_GT(bombs.size(), 30u);
  const std::vector<std::string> channels = {"HEALTH",
                                             "SIM.CONTROL",
                                             "MAPSTORE.REQUEST",
                                             "MAPSTORE.REPLY",
                                             "MAPSTORE.TILE_RESEND",
                                             "MAPSTORE.PUSH.TILES",
                                             "MAPSTORE.PUSH.TILE_BATCHES",
                                             "MAPSTORE.PUSH.MANIFEST",
                                             "MAPSTORE.PUSH.OBSTACLES",
                                             "MAPSTORE.PUSH.OCTOMAP",
                                             "p3at.CMD_VEL",
                                             "p3at.GOAL",
                                             "p3at.LIDAR",
                                             "p3at.LIDAR_RANGES",
                                             "p3at.SCAN",
                                             "p3at.ODOM",
                                             "p3at.POSE",
                                             "p3at.IMU",
                                             "p3at.MAP.CONTROL",
                                             "p3at.MAP.TILE_RESEND",
                                             "p3at.MAP.TILES",
                                             "p3at.MAP.MANIFEST",
                                             "p3at.MAP.OCCUPANCY",
                                             "p3at.MAP.OBSTACLES",
                                             "p3at.MAP.OCTOMAP"};
  lcm::LCM bus(procs.url());
  ASSERT_TRUE(bus.good());
  int sent = 0;
  for (const std::string& channel : channels) {
    for (const auto& bomb : bombs) {
      bus.publish(channel, bomb.data(), static_cast<unsigned>(bomb.size()));
      // Paced: the bombs must reach the processes, not overflow their sockets.
      if (++sent % 50 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  const std::map<std::string, double> after = meter.Measure(3.0);
  for (size_t i = 0; i < pids.size(); ++i) {
    const double rss = RssMb(pids[i]);
    ASSERT_GT(rss, 0.0) << names[i] << " died";
    EXPECT_LT(rss - rss_before[i], 50.0)
        << names[i] << " grew from " << rss_before[i] << " MB to " << rss << " MB";
  }
  // The rates each process keeps (the sim's sensors, the mapper's maps, the navigator's status,
  // every heartbeat): at least 70 % of what they were.
  for (const char* channel :
       {"p3at.LIDAR_RANGES", "p3at.POSE", "p3at.MAP.MANIFEST", "p3at.NAV_STATUS", "HEALTH"}) {
    const double was = before.count(channel) ? before.at(channel) : 0.0;
    const double is = after.count(channel) ? after.at(channel) : 0.0;
    EXPECT_GT(was, 0.0) << channel << " was silent before the bombs";
    EXPECT_GE(is, 0.7 * was) << channel << ": " << was << " Hz before the bombs, " << is
                             << " Hz after";
  }
  std::printf("%d bombs (%zu per channel) sent; rates before -> after:", sent, bombs.size());
  for (const auto& [channel, rate] : before) {
    std::printf(" %s %.1f->%.1f", channel.c_str(), rate,
                after.count(channel) ? after.at(channel) : 0.0);
  }
  std::printf("\n");
  ExpectStatusWithinASecondThenDown(procs, run_dir);
}

TEST(LaunchIntegrationTest, RequiredProcessFailingForGoodStopsTheGraph) {
  ProcessSet procs(PrivateLcmUrl());
  const std::string path = procs.dir() + "/failing.yaml";
  {
    std::ofstream out(path);
    out << "name: failing\nlcm_url: " << procs.url() << "\nprocesses:\n"
        << "  watcher:\n    command: " << BinPath("cairn-spy") << "\n    args: [--refresh, '10']\n"
        << "  broken:\n    command: /bin/false\n    ready: {heartbeat: false}\n"
        << "    restart: on-failure\n    max_restarts: 2\n    backoff_s: 0.1\n";
  }
  ChildProcess& launcher = procs.StartRaw(
      "cairn-launch", {BinPath("cairn-launch"), "up", path, "--run-dir", procs.dir() + "/run"});
  auto exit = launcher.WaitExit(60.0);
  ASSERT_TRUE(exit.has_value()) << "the launcher did not stop";
  EXPECT_TRUE(WIFEXITED(*exit));
  EXPECT_EQ(WEXITSTATUS(*exit), 1);
  EXPECT_NE(
      launcher.Log().find("required process 'broken' failed for good: exited 1 after 2 restarts"),
      std::string::npos)
      << launcher.Log();
}

TEST(LaunchIntegrationTest, InvalidGraphIsRefusedBeforeAnythingStarts) {
  ProcessSet procs(PrivateLcmUrl());
  const std::string path = procs.dir() + "/bad.yaml";
  {
    std::ofstream out(path);
    out << "processes:\n  a:\n    command: " << BinPath("cairn-spy") << "\n    depends_on: [b]\n"
        << "  b:\n    command: " << BinPath("cairn-spy") << "\n    depends_on: [a]\n";
  }
  ChildProcess& launcher = procs.StartRaw(
      "cairn-launch", {BinPath("cairn-launch"), "up", path, "--run-dir", procs.dir() + "/run"});
  auto exit = launcher.WaitExit(20.0);
  ASSERT_TRUE(exit.has_value());
  EXPECT_EQ(WEXITSTATUS(*exit), 2);
  EXPECT_NE(launcher.Log().find("bad.yaml:5: dependency cycle: a -> b -> a"), std::string::npos)
      << launcher.Log();
  EXPECT_FALSE(std::ifstream(procs.dir() + "/run/status.json").good());
}

}  // namespace
}  // namespace cairn::testing
