#pragma once

#include <map>
#include <set>
#include <string>

#include "cairn/lcmt_health.hpp"
#include "services/launch/graph.h"
#include "services/launch/posix_runner.h"
#include "services/launch/status.h"
#include "services/launch/supervisor.h"
#include "services/runtime/channel_meter.h"
#include "services/runtime/node.h"

/// @file
/// The LCM side of cairn-launch: feeds heartbeats and measured channel rates into the
/// supervisor, ticks it, writes <run_dir>/status.json and rotates the processes' logs.

namespace cairn::launch {

class LaunchService {
 public:
  LaunchService(runtime::Node* node, Supervisor* supervisor, ProcessRunner* runner,
                std::string status_path);
  /// Runs until the graph is down. Returns the process exit code: 0, or 1 when a required
  /// process failed for good.
  int Run();
  GraphStatus MakeStatus(double now_s);

 private:
  void OnMessage(const std::string& channel, const void* data, int size);
  void Tick();
  void RotateLogs();
  double Now() const;

  runtime::Node* node_;
  Supervisor* supervisor_;
  ProcessRunner* runner_;
  std::string status_path_;
  runtime::ChannelMeter meter_;
  ProcSampler sampler_;
  std::map<int, cairn::lcmt_health> health_by_pid_;
  std::string message_;
  bool announced_ready_{false};
  std::set<std::string> rotate_failed_;
};

/// Runs `graph` in the foreground on `lcm_url` until it is down (a signal, or a required process
/// failed for good): the supervisor, its process runner and the service. Returns the process exit
/// code (0, 1 when a required process failed for good, 2 when the bus or a process could not
/// start).
int RunGraph(const GraphSpec& graph, const std::string& lcm_url);

}  // namespace cairn::launch
