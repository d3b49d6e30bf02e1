#pragma once

#include <sys/types.h>

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "services/launch/graph.h"

/// @file
/// The supervisor: the pure state machine of cairn-launch. It starts processes in dependency
/// order once their dependencies are ready, decides readiness from heartbeats and channel rates,
/// restarts with back-off per policy, and stops everything in reverse order. Process creation and
/// the clock are injected (ProcessRunner), so the logic is unit-tested without real processes.

namespace cairn::launch {

/// Spawns and signals real (or fake) processes.
class ProcessRunner {
 public:
  virtual ~ProcessRunner() = default;
  /// Starts the process; returns its pid, or -1 with *error set.
  virtual pid_t Spawn(const ProcessSpec& spec, std::string* error) = 0;
  /// Signals the process (and its process group).
  virtual void Signal(pid_t pid, int signal) = 0;
  /// Non-blocking: the wait status if the process has exited.
  virtual std::optional<int> Poll(pid_t pid) = 0;
  /// The process group of a running pid (-1 when unknown or gone). Every spawned process leads
  /// a group of its own, so a process a wrapper script started is in its wrapper's group.
  virtual pid_t GroupOf(pid_t /*pid*/) { return -1; }
  /// Where the process's output goes (empty: nowhere the launcher rotates).
  virtual std::string LogPath(const std::string& /*name*/) const { return {}; }
};

enum class ProcState {
  kPending,   ///< waiting for its dependencies to be ready
  kStarting,  ///< running, not yet ready
  kReady,
  kBackoff,   ///< exited; waiting to restart
  kStopping,
  kExited,    ///< finished for good (exit 0 under never/on-failure, or stopped)
  kFailed,    ///< failed for good
};
const char* ProcStateName(ProcState state);

struct ProcStatus {
  std::string name;
  std::string robot;
  ProcState state{ProcState::kPending};
  pid_t pid{-1};
  int restarts{0};         ///< every restart since launch (what status shows)
  int recent_restarts{0};  ///< restarts since it was last stable: the back-off and max_restarts
  int last_exit_status{-1};  ///< raw wait status
  std::string last_exit;     ///< "exited 3", "killed by SIGKILL"
  double state_since_s{0.0};
  double next_start_s{0.0};
  bool heartbeat_ready{false};
  double last_alive_s{0.0};  ///< its last heartbeat (or ready-channel rate) after it started
  bool hung{false};          ///< stopped for sending no heartbeat; restarted per policy
  double hung_since_s{0.0};
};

class Supervisor {
 public:
  using EventSink = std::function<void(const std::string& line)>;
  Supervisor(GraphSpec graph, ProcessRunner* runner, EventSink events);

  /// Advances the state machine at time now_s (seconds, monotonic).
  void Tick(double now_s);
  /// A heartbeat from `pid` in state READY (or not) at now_s. It counts for the process the
  /// supervisor started with that pid, or whose process group holds it (a process started
  /// through a wrapper script); a heartbeat from any other pid is ignored, whatever names it
  /// carries: a forged HEALTH cannot mark a process ready or keep a hung one alive. False when
  /// it was ignored.
  bool OnHeartbeat(pid_t pid, const std::string& process, const std::string& robot, bool ready,
                   double now_s);
  /// Current rate of a channel as measured by the caller.
  void SetChannelRate(const std::string& channel, double rate_hz);
  /// Begins an orderly stop of everything (reverse start order).
  void RequestStop(double now_s);

  bool stopping() const { return stopping_; }
  /// True when every process has exited or failed (after a stop, or when nothing is left).
  bool AllDown() const;
  /// The first required process that failed for good, with the reason.
  std::optional<std::string> FatalFailure() const { return fatal_; }
  /// True when every process is ready (or finished cleanly).
  bool AllReady() const;
  const std::vector<ProcStatus>& statuses() const { return statuses_; }
  const GraphSpec& graph() const { return graph_; }
  const std::map<std::string, double>& channel_rates() const { return rates_; }

 private:
  ProcStatus& StatusOf(const std::string& name);
  const ProcessSpec& SpecOf(const std::string& name) const;
  bool DependenciesReady(const ProcessSpec& spec) const;
  void Start(ProcStatus& st, const ProcessSpec& spec, double now_s);
  void HandleExit(ProcStatus& st, const ProcessSpec& spec, int status, double now_s);
  void SetState(ProcStatus& st, ProcState state, double now_s);
  void CheckReady(ProcStatus& st, const ProcessSpec& spec, double now_s);
  void CheckLiveness(ProcStatus& st, const ProcessSpec& spec, double now_s);

  GraphSpec graph_;
  ProcessRunner* runner_;
  EventSink events_;
  std::vector<ProcStatus> statuses_;
  std::map<std::string, double> rates_;
  std::vector<std::string> start_order_;
  bool stopping_{false};
  double stop_started_s_{0.0};
  std::optional<std::string> fatal_;
};

/// "exited 0", "exited 3", "killed by SIGKILL".
std::string DescribeWaitStatus(int status);

}  // namespace cairn::launch
