#include "services/launch/supervisor.h"

#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace cairn::launch {

const char* ProcStateName(ProcState state) {
  switch (state) {
    case ProcState::kPending: return "pending";
    case ProcState::kStarting: return "starting";
    case ProcState::kReady: return "ready";
    case ProcState::kBackoff: return "backoff";
    case ProcState::kStopping: return "stopping";
    case ProcState::kExited: return "exited";
    case ProcState::kFailed: return "failed";
  }
  return "?";
}

std::string DescribeWaitStatus(int status) {
  if (WIFEXITED(status)) return "exited " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = sigabbrev_np(sig);
    return std::string("killed by SIG") + (name ? name : std::to_string(sig).c_str());
  }
  return "status " + std::to_string(status);
}

namespace {

// "2.5", "10": seconds for event lines.
std::string Seconds(double s) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g", s);
  return text;
}

}  // namespace

Supervisor::Supervisor(GraphSpec graph, ProcessRunner* runner, EventSink events)
    : graph_(std::move(graph)), runner_(runner), events_(std::move(events)) {
  for (const auto& spec : graph_.processes) {
    ProcStatus st;
    st.name = spec.name;
    st.robot = spec.robot;
    statuses_.push_back(st);
  }
  start_order_ = graph_.StartOrder();
}

ProcStatus& Supervisor::StatusOf(const std::string& name) {
  for (auto& st : statuses_) {
    if (st.name == name) return st;
  }
  throw std::out_of_range("no process " + name);
}

const ProcessSpec& Supervisor::SpecOf(const std::string& name) const { return *graph_.Find(name); }

void Supervisor::SetState(ProcStatus& st, ProcState state, double now_s) {
  if (st.state == state) return;
  st.state = state;
  st.state_since_s = now_s;
}

bool Supervisor::DependenciesReady(const ProcessSpec& spec) const {
  for (const auto& dep : spec.depends_on) {
    for (const auto& st : statuses_) {
      if (st.name == dep && st.state != ProcState::kReady) return false;
    }
  }
  return true;
}

void Supervisor::Start(ProcStatus& st, const ProcessSpec& spec, double now_s) {
  std::string error;
  const pid_t pid = runner_->Spawn(spec, &error);
  st.heartbeat_ready = false;
  st.hung = false;
  if (pid <= 0) {
    events_("process '" + spec.name + "' could not start: " + error);
    st.pid = -1;
    st.last_exit = "spawn failed: " + error;
    SetState(st, ProcState::kFailed, now_s);
    if (spec.required && !fatal_) fatal_ = "process '" + spec.name + "' could not start: " + error;
    return;
  }
  st.pid = pid;
  SetState(st, ProcState::kStarting, now_s);
  events_("started '" + spec.name + "' (pid " + std::to_string(pid) +
          (st.restarts ? ", restart " + std::to_string(st.restarts) : std::string()) + ")");
}

void Supervisor::HandleExit(ProcStatus& st, const ProcessSpec& spec, int status, double now_s) {
  st.last_exit_status = status;
  st.last_exit = DescribeWaitStatus(status);
  if (st.hung) {
    st.last_exit = "hung (no heartbeat for " + Seconds(spec.liveness_timeout_s) + " s), " +
                   st.last_exit;
  }
  const bool hung = st.hung;
  st.hung = false;
  st.pid = -1;
  st.heartbeat_ready = false;
  if (stopping_ || (st.state == ProcState::kStopping && !hung)) {
    SetState(st, ProcState::kExited, now_s);
    events_("'" + spec.name + "' stopped (" + st.last_exit + ")");
    return;
  }
  const bool clean = !hung && WIFEXITED(status) && WEXITSTATUS(status) == 0;
  const bool restart = spec.restart == RestartPolicy::kAlways ||
                       (spec.restart == RestartPolicy::kOnFailure && !clean);
  if (!restart) {
    SetState(st, clean ? ProcState::kExited : ProcState::kFailed, now_s);
    events_("'" + spec.name + "' " + st.last_exit + (clean ? "" : ", not restarted (restart: never)"));
    if (!clean && spec.required && !fatal_) {
      fatal_ = "required process '" + spec.name + "' failed: " + st.last_exit;
    }
    return;
  }
  if (st.recent_restarts >= spec.max_restarts) {
    SetState(st, ProcState::kFailed, now_s);
    events_("'" + spec.name + "' " + st.last_exit + "; gave up after " +
            std::to_string(st.recent_restarts) + " restarts");
    if (spec.required && !fatal_) {
      fatal_ = "required process '" + spec.name + "' failed for good: " + st.last_exit + " after " +
               std::to_string(st.recent_restarts) + " restarts";
    }
    return;
  }
  const double delay =
      std::min(spec.max_backoff_s,
               spec.backoff_s * std::pow(2.0, static_cast<double>(st.recent_restarts)));
  st.next_start_s = now_s + delay;
  SetState(st, ProcState::kBackoff, now_s);
  events_("'" + spec.name + "' " + st.last_exit + "; restarting in " + Seconds(delay) + " s");
}

void Supervisor::Tick(double now_s) {
  // Collect exits.
  for (auto& st : statuses_) {
    if (st.pid <= 0) continue;
    if (auto status = runner_->Poll(st.pid)) HandleExit(st, SpecOf(st.name), *status, now_s);
  }
  if (stopping_) {
    // Stop in reverse start order: a process is signalled once everything started after it
    // (its dependants) is down; SIGKILL after its grace period.
    for (auto it = start_order_.rbegin(); it != start_order_.rend(); ++it) {
      ProcStatus& st = StatusOf(*it);
      const ProcessSpec& spec = SpecOf(*it);
      if (st.pid <= 0) {
        if (st.state != ProcState::kFailed) SetState(st, ProcState::kExited, now_s);
        continue;
      }
      bool dependants_down = true;
      for (const auto& other : graph_.processes) {
        if (std::find(other.depends_on.begin(), other.depends_on.end(), spec.name) !=
                other.depends_on.end() &&
            StatusOf(other.name).pid > 0) {
          dependants_down = false;
        }
      }
      if (!dependants_down) continue;
      if (st.state != ProcState::kStopping) {
        runner_->Signal(st.pid, spec.stop_signal);
        SetState(st, ProcState::kStopping, now_s);
      } else if (now_s - st.state_since_s > spec.grace_s) {
        events_("'" + spec.name + "' did not stop within " + Seconds(spec.grace_s) + " s; SIGKILL");
        runner_->Signal(st.pid, SIGKILL);
        st.state_since_s = now_s;  // wait again before another kill
      }
    }
    return;
  }
  for (const auto& name : start_order_) {
    ProcStatus& st = StatusOf(name);
    const ProcessSpec& spec = SpecOf(name);
    switch (st.state) {
      case ProcState::kPending:
        if (DependenciesReady(spec)) Start(st, spec, now_s);
        break;
      case ProcState::kBackoff:
        if (now_s >= st.next_start_s && DependenciesReady(spec)) {
          ++st.restarts;
          ++st.recent_restarts;
          Start(st, spec, now_s);
        }
        break;
      case ProcState::kStarting:
        CheckReady(st, spec, now_s);
        break;
      case ProcState::kReady:
        CheckLiveness(st, spec, now_s);
        break;
      case ProcState::kStopping:
        // A hung process was sent its stop signal; one that ignores it is killed after its
        // grace period.
        if (st.hung && now_s - st.hung_since_s > spec.grace_s) {
          runner_->Signal(st.pid, SIGKILL);
          st.hung_since_s = now_s;
        }
        break;
      default:
        break;
    }
  }
}

void Supervisor::CheckReady(ProcStatus& st, const ProcessSpec& spec, double now_s) {
  bool ready = false;
  if (spec.ready.heartbeat && st.heartbeat_ready) ready = true;
  if (!spec.ready.channel.empty()) {
    auto r = rates_.find(spec.ready.channel);
    const bool rate_ok = r != rates_.end() && r->second >= spec.ready.min_rate_hz;
    ready = spec.ready.heartbeat ? (ready && rate_ok) : rate_ok;
  }
  if (!spec.ready.heartbeat && spec.ready.channel.empty()) ready = true;
  if (ready) {
    SetState(st, ProcState::kReady, now_s);
    st.last_alive_s = now_s;
    events_("'" + spec.name + "' is ready");
  } else if (now_s - st.state_since_s > spec.ready.timeout_s) {
    events_("'" + spec.name + "' not ready after " + Seconds(spec.ready.timeout_s) +
            " s; killing it");
    runner_->Signal(st.pid, SIGKILL);
    st.state_since_s = now_s;  // the exit is handled on a later tick
  }
}

void Supervisor::CheckLiveness(ProcStatus& st, const ProcessSpec& spec, double now_s) {
  // A stable process earns its restarts back: the next failure backs off from the start.
  if (st.recent_restarts > 0 && spec.reset_restarts_after_s > 0 &&
      now_s - st.state_since_s >= spec.reset_restarts_after_s) {
    events_("'" + spec.name + "' ready for " + Seconds(spec.reset_restarts_after_s) +
            " s; its back-off and restart count towards max_restarts (" +
            std::to_string(st.recent_restarts) + ") reset");
    st.recent_restarts = 0;
  }
  if (!spec.ready.channel.empty()) {
    auto r = rates_.find(spec.ready.channel);
    if (r != rates_.end() && r->second >= spec.ready.min_rate_hz) st.last_alive_s = now_s;
  } else if (!spec.ready.heartbeat) {
    return;  // nothing to watch: ready meant started
  }
  if (spec.liveness_timeout_s <= 0 || now_s - st.last_alive_s <= spec.liveness_timeout_s) return;
  st.hung = true;
  st.hung_since_s = now_s;
  SetState(st, ProcState::kStopping, now_s);
  events_("'" + spec.name + "' (pid " + std::to_string(st.pid) + ") " +
          (spec.ready.channel.empty() ? "sent no heartbeat"
                                      : "published too slowly on " + spec.ready.channel) +
          " for " + Seconds(now_s - st.last_alive_s) + " s after it was ready; stopping it");
  runner_->Signal(st.pid, spec.stop_signal);
}

bool Supervisor::OnHeartbeat(pid_t pid, const std::string& /*process*/,
                             const std::string& /*robot*/, bool ready, double now_s) {
  // Only the pid counts (names on the bus are anyone's to send); a process a wrapper script
  // started runs in the wrapper's process group.
  if (pid <= 0) return false;
  ProcStatus* match = nullptr;
  for (auto& st : statuses_) {
    if (st.pid > 0 && st.pid == pid) match = &st;
  }
  if (match == nullptr) {
    const pid_t group = runner_->GroupOf(pid);
    for (auto& st : statuses_) {
      if (st.pid > 0 && group == st.pid) match = &st;
    }
  }
  if (match == nullptr) return false;
  match->heartbeat_ready = ready;
  match->last_alive_s = now_s;
  return true;
}

void Supervisor::SetChannelRate(const std::string& channel, double rate_hz) { rates_[channel] = rate_hz; }

void Supervisor::RequestStop(double now_s) {
  if (stopping_) return;
  stopping_ = true;
  stop_started_s_ = now_s;
  for (auto& st : statuses_) {
    if (st.pid <= 0 && st.state != ProcState::kFailed) SetState(st, ProcState::kExited, now_s);
  }
}

bool Supervisor::AllDown() const {
  return std::all_of(statuses_.begin(), statuses_.end(), [](const ProcStatus& st) {
    return st.pid <= 0 && (st.state == ProcState::kExited || st.state == ProcState::kFailed);
  });
}

bool Supervisor::AllReady() const {
  return std::all_of(statuses_.begin(), statuses_.end(), [](const ProcStatus& st) {
    return st.state == ProcState::kReady || st.state == ProcState::kExited;
  });
}

}  // namespace cairn::launch
