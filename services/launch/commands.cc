#include "services/launch/commands.h"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "services/launch/status.h"

namespace cairn::launch {
namespace {

namespace fs = std::filesystem;

double SecondsLeft(std::chrono::steady_clock::time_point deadline) {
  return std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
}

std::chrono::steady_clock::time_point DeadlineIn(double seconds) {
  return std::chrono::steady_clock::now() +
         std::chrono::duration_cast<std::chrono::steady_clock::duration>(
             std::chrono::duration<double>(seconds));
}

// Whether a process the launcher's status lists still runs.
bool OrphansLeft(const std::string& run_dir) {
  std::string error;
  auto status = ReadStatusFile(run_dir + "/status.json", &error);
  if (!status) return false;
  for (const auto& p : status->processes) {
    if (ProcessAlive(p.pid)) return true;
  }
  return false;
}

// Kills the processes a dead launcher left (their process groups first).
void KillOrphans(const std::string& run_dir) {
  std::string error;
  auto status = ReadStatusFile(run_dir + "/status.json", &error);
  if (!status) return;
  for (const auto& p : status->processes) {
    if (ProcessAlive(p.pid)) {
      kill(-p.pid, SIGKILL);
      kill(p.pid, SIGKILL);
    }
  }
}

// Forks into the background: the parent prints where the graph runs and returns true.
bool DetachParent(const GraphSpec& graph, int* exit_code) {
  const pid_t pid = fork();
  if (pid < 0) {
    std::fprintf(stderr, "cairn-launch: cannot fork: %s\n", std::strerror(errno));
    *exit_code = 2;
    return true;
  }
  if (pid > 0) {
    std::printf("graph '%s' starting in the background (launcher pid %d); run dir %s\n",
                graph.name.c_str(), pid, graph.run_dir.c_str());
    *exit_code = 0;
    return true;
  }
  setsid();
  const std::string log = graph.run_dir + "/launch.log";
  if (!freopen(log.c_str(), "a", stdout) || !freopen(log.c_str(), "a", stderr)) _exit(2);
  if (!freopen("/dev/null", "r", stdin)) _exit(2);
  return false;
}

}  // namespace

std::vector<std::string> SearchDirs(const std::string& path_list) {
  std::vector<std::string> dirs;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) dirs.push_back(self.parent_path().string());
  std::stringstream ss(path_list);
  std::string dir;
  while (std::getline(ss, dir, ':')) {
    if (!dir.empty()) dirs.push_back(dir);
  }
  return dirs;
}

std::string GraphPath(const std::string& graph_arg) {
  if (fs::exists(graph_arg)) return graph_arg;
  const std::string candidate = "config/graphs/" + graph_arg + ".yaml";
  if (fs::exists(candidate)) return candidate;
  return graph_arg;
}

std::string RunDirFor(const std::string& graph_arg, const std::string& run_dir_flag,
                      const std::vector<std::string>& search_dirs) {
  if (!run_dir_flag.empty()) return run_dir_flag;
  try {
    return LoadGraph(GraphPath(graph_arg), search_dirs).run_dir;
  } catch (const std::exception&) {
    return "var/run/" + fs::path(graph_arg).stem().string();
  }
}

bool ProcessAlive(int pid) {
  if (pid <= 0 || (kill(pid, 0) != 0 && errno != EPERM)) return false;
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string content;
  std::getline(stat, content);
  const auto paren = content.rfind(')');
  return paren == std::string::npos || paren + 2 >= content.size() || content[paren + 2] != 'Z';
}

int CmdStatus(const std::string& run_dir) {
  std::string error;
  auto status = ReadStatusFile(run_dir + "/status.json", &error);
  if (!status) {
    std::fprintf(stderr, "cairn-launch: %s\n", error.c_str());
    return 1;
  }
  if (!ProcessAlive(status->launcher_pid) && status->state != "stopped" &&
      status->state != "failed") {
    status->state = "dead";
    status->message =
        "the launcher (pid " + std::to_string(status->launcher_pid) + ") is not running";
  }
  std::fputs(FormatStatusTable(*status).c_str(), stdout);
  return 0;
}

int CmdWait(const std::string& run_dir, double timeout_s) {
  const auto deadline = DeadlineIn(timeout_s);
  while (SecondsLeft(deadline) > 0.0) {
    std::string error;
    auto status = ReadStatusFile(run_dir + "/status.json", &error);
    if (status) {
      if (status->state == "ready") return 0;
      const bool alive = ProcessAlive(status->launcher_pid);
      if (status->state == "failed" || status->state == "stopped" || !alive) {
        std::fprintf(stderr, "cairn-launch: graph '%s' is %s%s%s\n", status->graph.c_str(),
                     alive ? status->state.c_str() : "not running",
                     status->message.empty() ? "" : ": ", status->message.c_str());
        return 1;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  std::fprintf(stderr, "cairn-launch: graph in %s not ready after %.0f s\n", run_dir.c_str(),
               timeout_s);
  return 2;
}

int CmdDown(const std::string& run_dir, double timeout_s) {
  std::ifstream pid_file(run_dir + "/launch.pid");
  int pid = -1;
  if (!(pid_file >> pid) || !ProcessAlive(pid)) {
    std::fprintf(stderr, "cairn-launch: no running graph in %s\n", run_dir.c_str());
    KillOrphans(run_dir);  // children of a launcher that died are still ours to stop
    return 0;
  }
  kill(pid, SIGTERM);
  const auto deadline = DeadlineIn(timeout_s);
  while (ProcessAlive(pid) && SecondsLeft(deadline) > 0.0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (ProcessAlive(pid)) {
    std::fprintf(stderr, "cairn-launch: launcher %d did not stop within %.0f s; killing it\n", pid,
                 timeout_s);
    kill(pid, SIGKILL);
    // Its children are sent SIGTERM as it dies; any still running after a grace is killed.
    const auto grace = DeadlineIn(5.0);
    while (OrphansLeft(run_dir) && SecondsLeft(grace) > 0.0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    KillOrphans(run_dir);
    return 1;
  }
  std::printf("graph in %s stopped\n", run_dir.c_str());
  return 0;
}

int CmdCheck(const std::string& graph_arg, const std::vector<std::string>& search_dirs) {
  try {
    const auto graph = LoadGraph(GraphPath(graph_arg), search_dirs);
    std::printf("graph '%s' is valid; start order:", graph.name.c_str());
    for (const auto& name : graph.StartOrder()) std::printf(" %s", name.c_str());
    std::printf("\n");
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn-launch: %s\n", e.what());
    return 2;
  }
}

std::optional<UpPlan> PrepareUp(const std::string& graph_arg, const std::string& lcm_url,
                                const std::string& run_dir_flag, bool detach,
                                const std::vector<std::string>& search_dirs, int* exit_code) {
  *exit_code = 2;
  UpPlan plan;
  try {
    plan.graph = LoadGraph(GraphPath(graph_arg), search_dirs);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn-launch: %s\n", e.what());
    return std::nullopt;
  }
  GraphSpec& graph = plan.graph;
  if (!run_dir_flag.empty()) graph.run_dir = run_dir_flag;
  plan.lcm_url = lcm_url.empty() ? graph.lcm_url : lcm_url;
  std::error_code ec;
  fs::create_directories(graph.run_dir + "/logs", ec);
  if (ec) {
    std::fprintf(stderr, "cairn-launch: cannot create %s: %s\n", graph.run_dir.c_str(),
                 ec.message().c_str());
    return std::nullopt;
  }
  std::ifstream old_pid_file(graph.run_dir + "/launch.pid");
  int old = -1;
  if ((old_pid_file >> old) && old != getpid() && ProcessAlive(old)) {
    std::fprintf(stderr,
                 "cairn-launch: graph '%s' already runs (launcher pid %d); use 'down' first\n",
                 graph.name.c_str(), old);
    return std::nullopt;
  }
  fs::remove(graph.run_dir + "/status.json", ec);
  if (detach && DetachParent(graph, exit_code)) return std::nullopt;
  std::ofstream pid_file(graph.run_dir + "/launch.pid", std::ios::trunc);
  pid_file << getpid() << "\n";
  *exit_code = 0;
  return plan;
}

void FinishUp(const UpPlan& plan) {
  std::error_code ec;
  fs::remove(plan.graph.run_dir + "/launch.pid", ec);
}

}  // namespace cairn::launch
