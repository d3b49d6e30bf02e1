#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <sys/types.h>

#include "cairn/lcmt_health.hpp"

/// @file
/// Integration-test harness: real processes on a private LCM bus.
///
/// - PrivateLcmUrl() gives each test its own multicast port (ttl=0, never leaves the host).
/// - ChildProcess starts an executable with its output captured to a log file and kills its
///   process group when destroyed.
/// - ProcessSet prints the logs of every process it started when the test failed.
/// - WaitFor polls a condition with a bound (no sleep-and-hope).
/// - Bus subscribes on the private URL and keeps the newest message per channel.

namespace cairn::testing {

/// udpm://239.255.76.67:<a free port>?ttl=0, different for every call in a run.
std::string PrivateLcmUrl();
/// build/bin/<name>.
std::string BinPath(const std::string& name);
/// The source tree (for config files and worlds).
std::string SourcePath(const std::string& relative);
/// A fresh directory under build/test-tmp/<test name>, removed first if it exists.
std::string TestTempDir();
/// The shipped mapper configuration (config/mapping/mapper.yaml) with the OctoMap off (the
/// costliest part on a shared machine, for tests that do not look at it), written to
/// <dir>/mapper.yaml; returns that path.
std::string MapperConfigWithoutOctomap(const std::string& dir);

/// The last `lines` lines of a text file ("" when it cannot be read): a failure message quotes
/// the events of the process that decided, before the full logs.
std::string TailOfFile(const std::string& path, int lines);

class ChildProcess {
 public:
  /// Starts argv[0] with argv; env entries "K=V" are added to the environment. Output goes to
  /// log_path. @throws std::runtime_error if fork/exec setup fails.
  ChildProcess(std::vector<std::string> argv, std::vector<std::string> env, std::string log_path);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  const std::string& name() const { return name_; }
  const std::string& log_path() const { return log_path_; }
  bool Running();
  void Signal(int signal);
  /// Waits for exit; returns the raw wait status, or nullopt on timeout.
  std::optional<int> WaitExit(double timeout_s);
  /// SIGTERM, wait up to grace, then SIGKILL. Returns the wait status.
  int Stop(double grace_s = 5.0);
  std::string Log() const;

 private:
  std::string name_;
  std::string log_path_;
  pid_t pid_{-1};
  std::optional<int> status_;
};

/// Owns processes of one test; prints their logs in the destructor when the test failed.
class ProcessSet {
 public:
  explicit ProcessSet(std::string url);
  /// Logs in `dir` (created if missing) instead of the test's own folder: for several sets side
  /// by side in one test.
  ProcessSet(std::string url, std::string dir);
  ~ProcessSet();
  const std::string& url() const { return url_; }
  const std::string& dir() const { return dir_; }
  /// Starts build/bin/<exe> with args plus --lcm-url.
  ChildProcess& Start(const std::string& exe, std::vector<std::string> args,
                      std::vector<std::string> env = {});
  /// Starts an arbitrary command (no --lcm-url added).
  ChildProcess& StartRaw(const std::string& label, std::vector<std::string> argv,
                         std::vector<std::string> env = {});
  /// Also prints every *.log file of `dir` on failure (a cairn-launch run's process logs).
  void AddLogDir(const std::string& dir) { log_dirs_.push_back(dir); }
  void PrintLogs() const;

 private:
  std::string url_;
  std::string dir_;
  std::vector<std::string> log_dirs_;
  std::vector<std::unique_ptr<ChildProcess>> processes_;
};

/// Polls `condition` (calling `pump` in between, for example Bus::Pump) until it holds or the
/// timeout passes. Returns the final value of the condition.
bool WaitFor(const std::function<bool()>& condition, double timeout_s,
             const std::function<void()>& pump = nullptr);

/// A subscriber on the test's bus.
class Bus {
 public:
  explicit Bus(const std::string& url);
  lcm::LCM& lcm() { return lcm_; }
  /// Handles traffic for up to timeout_ms.
  void Pump(int timeout_ms = 20);
  /// Raw bytes of the newest message per channel (all channels).
  bool Seen(const std::string& channel) const { return last_.count(channel) > 0; }
  int64_t Count(const std::string& channel) const;
  template <typename Msg>
  std::optional<Msg> Last(const std::string& channel) const {
    auto it = last_.find(channel);
    if (it == last_.end()) return std::nullopt;
    Msg m;
    if (m.decode(it->second.data(), 0, static_cast<int>(it->second.size())) < 0)
      return std::nullopt;
    return m;
  }
  /// Newest heartbeat of a process (by process name, and robot when given).
  std::optional<cairn::lcmt_health> Health(const std::string& process,
                                           const std::string& robot = "") const;
  template <typename Msg>
  bool Publish(const std::string& channel, const Msg& msg) {
    return lcm_.publish(channel, &msg) == 0;
  }
  /// Every message on a channel since the start, decoded (for channels you asked to keep).
  void Keep(const std::string& channel) { keep_[channel]; }
  const std::vector<std::vector<uint8_t>>& Kept(const std::string& channel) {
    return keep_[channel];
  }
  /// Forgets what was kept on a channel (it stays kept from now on).
  void ClearKept(const std::string& channel) { keep_[channel].clear(); }

 private:
  lcm::LCM lcm_;
  std::map<std::string, std::vector<uint8_t>> last_;
  std::map<std::string, int64_t> counts_;
  std::map<std::string, cairn::lcmt_health> health_;
  std::map<std::string, std::vector<std::vector<uint8_t>>> keep_;
};

/// Sends a pose goal to `robot`'s navigator, again every second until its status names the
/// goal (a message on the bus can be lost; re-sending a goal id is idempotent). Returns whether
/// the navigator took it within timeout_s. `pump` handles traffic in between (bus.Pump(20)
/// when null).
bool SendPoseGoal(Bus& bus, const std::string& robot, int64_t goal_id, double x_m, double y_m,
                  double timeout_s, const std::function<void()>& pump = nullptr);

}  // namespace cairn::testing
