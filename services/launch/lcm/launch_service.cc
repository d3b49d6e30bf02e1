#include "services/launch/lcm/launch_service.h"

#include <cstdio>

#include <chrono>
#include <cstdint>

#include <sys/time.h>
#include <unistd.h>

#include "common/channels.h"
#include "common/log.h"

namespace cairn::launch {

LaunchService::LaunchService(runtime::Node* node, Supervisor* supervisor, ProcessRunner* runner,
                             std::string status_path)
    : node_(node), supervisor_(supervisor), runner_(runner), status_path_(std::move(status_path)) {
  node_->SubscribeRaw(".*", [this](const std::string& channel, const void* data, int size,
                                   int64_t) { OnMessage(channel, data, size); });
  node_->AddTimer(0.1, [this] { Tick(); });
  node_->AddTimer(1.0, [this] {
    WriteStatusFile(status_path_, MakeStatus(Now()));
    RotateLogs();
  });
}

double LaunchService::Now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

void LaunchService::OnMessage(const std::string& channel, const void* data, int size) {
  meter_.Record(channel, size, Now());
  if (channel != channels::kHealth) return;
  cairn::lcmt_health h{};
  if (h.decode(data, 0, size) < 0) return;
  if (h.process == "cairn-launch" && h.pid == getpid()) return;
  // Only heartbeats of the processes it started count, and only theirs are kept: a heartbeat
  // from any other pid (a peer's, or forged) neither marks anything ready nor grows the table.
  if (!supervisor_->OnHeartbeat(h.pid, h.process, h.robot,
                                h.state == cairn::lcmt_health::STATE_READY, Now())) {
    return;
  }
  health_by_pid_[h.pid] = h;
  if (health_by_pid_.size() > 2 * supervisor_->statuses().size()) {
    // Restarts leave the heartbeats of pids that are gone.
    std::map<int, cairn::lcmt_health> current;
    for (const auto& st : supervisor_->statuses()) {
      auto it = health_by_pid_.find(st.pid);
      if (it != health_by_pid_.end()) current.insert(*it);
    }
    health_by_pid_ = std::move(current);
  }
}

void LaunchService::Tick() {
  const double now = Now();
  for (const auto& [channel, rate] : meter_.Rates(now))
    supervisor_->SetChannelRate(channel, rate.rate_hz);
  if (runtime::ShutdownRequested() && !supervisor_->stopping()) {
    node_->Event("stopping graph '%s'", supervisor_->graph().name.c_str());
    message_ = "stopping on request";
    supervisor_->RequestStop(now);
  }
  if (auto fatal = supervisor_->FatalFailure(); fatal && !supervisor_->stopping()) {
    CAIRN_LOG_ERROR("%s; stopping graph '%s'", fatal->c_str(), supervisor_->graph().name.c_str());
    message_ = *fatal;
    supervisor_->RequestStop(now);
  }
  supervisor_->Tick(now);
  if (!announced_ready_ && supervisor_->AllReady()) {
    announced_ready_ = true;
    node_->SetState(runtime::HealthState::kReady, "graph ready");
    node_->Event("graph '%s' is ready", supervisor_->graph().name.c_str());
    WriteStatusFile(status_path_, MakeStatus(now));
  }
}

void LaunchService::RotateLogs() {
  const GraphSpec& graph = supervisor_->graph();
  if (graph.log_max_mb <= 0) return;
  const auto max_bytes = static_cast<std::uintmax_t>(graph.log_max_mb * 1024.0 * 1024.0);
  for (const auto& p : graph.processes) {
    const std::string path = runner_->LogPath(p.name);
    if (path.empty()) continue;
    std::string error;
    const auto rotated = RotateLog(path, max_bytes, graph.log_keep, &error);
    if (!error.empty()) {
      // Once per process: a log that cannot be rotated would otherwise say so every second.
      if (rotate_failed_.insert(p.name).second) {
        CAIRN_LOG_ERROR("cannot rotate the log of '%s': %s", p.name.c_str(), error.c_str());
      }
    } else if (rotated) {
      rotate_failed_.erase(p.name);
      node_->Event("rotated the log of '%s' at %.0f KB (keeping %d)", p.name.c_str(),
                   static_cast<double>(*rotated) / 1024.0, graph.log_keep);
    }
  }
}

GraphStatus LaunchService::MakeStatus(double now_s) {
  GraphStatus s;
  const GraphSpec& graph = supervisor_->graph();
  s.graph = graph.name;
  s.file = graph.file;
  s.lcm_url = node_->url();
  s.launcher_pid = static_cast<int>(getpid());
  if (supervisor_->FatalFailure()) {
    s.state = supervisor_->AllDown() ? "failed" : "stopping";
  } else if (supervisor_->stopping()) {
    s.state = supervisor_->AllDown() ? "stopped" : "stopping";
  } else {
    s.state = supervisor_->AllReady() ? "ready" : "starting";
  }
  s.message = message_;
  timeval tv{};
  gettimeofday(&tv, nullptr);
  s.updated_unix_s = tv.tv_sec + tv.tv_usec * 1e-6;
  for (const auto& st : supervisor_->statuses()) {
    ProcessRow row;
    row.name = st.name;
    row.robot = st.robot;
    row.state = ProcStateName(st.state);
    row.pid = st.pid;
    row.restarts = st.restarts;
    row.last_exit = st.last_exit;
    row.log = runner_->LogPath(st.name);
    if (st.pid > 0) {
      const ProcSample sample = sampler_.Sample(st.pid, now_s);
      row.cpu_percent = sample.cpu_percent;
      row.rss_mb = sample.rss_mb;
      row.uptime_s = now_s - st.state_since_s;
      auto h = health_by_pid_.find(st.pid);
      if (h != health_by_pid_.end()) {
        row.uptime_s = h->second.uptime_s;
        for (const auto& c : h->second.channels) {
          if (c.outgoing) row.channels_hz[c.channel] = c.rate_hz;
        }
      }
    }
    s.processes.push_back(row);
  }
  for (const auto& [channel, rate] : meter_.Rates(now_s))
    s.channel_rates_hz[channel] = rate.rate_hz;
  s.expected_rates_hz = graph.ExpectedRates();
  return s;
}

int LaunchService::Run() {
  node_->Event("starting graph '%s' (%zu processes) on %s", supervisor_->graph().name.c_str(),
               supervisor_->graph().processes.size(), node_->url().c_str());
  // Handle traffic and tick until every child is down (after a stop request, a fatal failure,
  // or because every process finished).
  while (!supervisor_->AllDown()) node_->SpinOnce(50);
  WriteStatusFile(status_path_, MakeStatus(Now()));
  if (auto fatal = supervisor_->FatalFailure()) {
    std::fprintf(stderr, "cairn-launch: graph '%s' stopped: %s\n",
                 supervisor_->graph().name.c_str(), fatal->c_str());
    return 1;
  }
  node_->Event("graph '%s' stopped", supervisor_->graph().name.c_str());
  return 0;
}

int RunGraph(const GraphSpec& graph, const std::string& lcm_url) {
  try {
    runtime::NodeOptions options;
    options.process_name = "cairn-launch";
    options.lcm_url = lcm_url;
    options.follow_sim_clock = false;
    runtime::Node node(options);
    PosixRunner runner(graph.run_dir + "/logs", node.url());
    Supervisor supervisor(graph, &runner,
                          [&node](const std::string& line) { node.Event("%s", line.c_str()); });
    LaunchService service(&node, &supervisor, &runner, graph.run_dir + "/status.json");
    return service.Run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn-launch: %s\n", e.what());
    return 2;
  }
}

}  // namespace cairn::launch
