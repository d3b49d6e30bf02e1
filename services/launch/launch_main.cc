// cairn-launch: starts a service graph from YAML, watches it, restarts, captures output.

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

#include "common/flags.h"
#include "common/log.h"
#include "services/launch/graph.h"
#include "services/launch/lcm/launch_service.h"
#include "services/launch/posix_runner.h"
#include "services/launch/status.h"
#include "services/launch/supervisor.h"
#include "services/runtime/node.h"

namespace fs = std::filesystem;
using namespace cairn;

namespace {

constexpr char kSummary[] =
    "Starts a graph of cairn processes from a YAML file, like procman's sheriff but headless.\n"
    "\n"
    "commands:\n"
    "  up GRAPH       start the graph in the foreground; Ctrl-C stops everything\n"
    "                 (--detach runs it in the background)\n"
    "  status [GRAPH] print the process table (state, pid, restarts, CPU, RSS, channel rates)\n"
    "  wait [GRAPH]   wait until every process is ready (exit 0), the graph failed (1) or\n"
    "                 --timeout passed (2)\n"
    "  down [GRAPH]   stop a running graph and wait for it\n"
    "  check GRAPH    validate a graph file and print its start order\n"
    "\n"
    "GRAPH is a file (config/graphs/demo.yaml) or a graph name (demo -> config/graphs/demo.yaml).\n"
    "The run directory (default var/run/<graph>) holds status.json, launch.pid and logs/.";

std::vector<std::string> BinDirs() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  return {self.parent_path().string()};
}

std::string GraphPath(const std::string& arg) {
  if (fs::exists(arg)) return arg;
  const std::string candidate = "config/graphs/" + arg + ".yaml";
  if (fs::exists(candidate)) return candidate;
  return arg;
}

std::string RunDirFor(const std::string& graph_arg, const std::string& run_dir_flag) {
  if (!run_dir_flag.empty()) return run_dir_flag;
  try {
    return launch::LoadGraph(GraphPath(graph_arg), BinDirs()).run_dir;
  } catch (const std::exception&) {
    return "var/run/" + fs::path(graph_arg).stem().string();
  }
}

// True while pid runs; a zombie (exited, not yet reaped by its parent) counts as gone.
bool Alive(int pid) {
  if (pid <= 0 || (kill(pid, 0) != 0 && errno != EPERM)) return false;
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string content;
  std::getline(stat, content);
  const auto paren = content.rfind(')');
  return paren == std::string::npos || paren + 2 >= content.size() || content[paren + 2] != 'Z';
}

int CmdStatus(const std::string& run_dir) {
  std::string error;
  auto status = launch::ReadStatusFile(run_dir + "/status.json", &error);
  if (!status) {
    std::fprintf(stderr, "cairn-launch: %s\n", error.c_str());
    return 1;
  }
  if (!Alive(status->launcher_pid) && status->state != "stopped" && status->state != "failed") {
    status->state = "dead";
    status->message = "the launcher (pid " + std::to_string(status->launcher_pid) + ") is not running";
  }
  std::fputs(launch::FormatStatusTable(*status).c_str(), stdout);
  return 0;
}

int CmdWait(const std::string& run_dir, double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  std::string last_state;
  while (std::chrono::steady_clock::now() < deadline) {
    std::string error;
    auto status = launch::ReadStatusFile(run_dir + "/status.json", &error);
    if (status) {
      if (status->state == "ready") return 0;
      if (status->state == "failed" || status->state == "stopped" ||
          (!Alive(status->launcher_pid))) {
        std::fprintf(stderr, "cairn-launch: graph '%s' is %s%s%s\n", status->graph.c_str(),
                     Alive(status->launcher_pid) ? status->state.c_str() : "not running",
                     status->message.empty() ? "" : ": ", status->message.c_str());
        return 1;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  std::fprintf(stderr, "cairn-launch: graph in %s not ready after %.0f s\n", run_dir.c_str(), timeout_s);
  return 2;
}

int CmdDown(const std::string& run_dir, double timeout_s) {
  std::ifstream pid_file(run_dir + "/launch.pid");
  int pid = -1;
  if (!(pid_file >> pid) || !Alive(pid)) {
    std::fprintf(stderr, "cairn-launch: no running graph in %s\n", run_dir.c_str());
    // Children of a launcher that died are still ours to stop.
    std::string error;
    if (auto status = launch::ReadStatusFile(run_dir + "/status.json", &error)) {
      for (const auto& p : status->processes) {
        if (Alive(p.pid)) {
          kill(-p.pid, SIGKILL);
          kill(p.pid, SIGKILL);
        }
      }
    }
    return 0;
  }
  kill(pid, SIGTERM);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (Alive(pid) && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (Alive(pid)) {
    std::fprintf(stderr, "cairn-launch: launcher %d did not stop within %.0f s; killing it\n", pid, timeout_s);
    kill(pid, SIGKILL);
    return 1;
  }
  std::printf("graph in %s stopped\n", run_dir.c_str());
  return 0;
}

int CmdUp(const std::string& graph_arg, std::string lcm_url, std::string run_dir_flag, bool detach) {
  launch::GraphSpec graph;
  try {
    graph = launch::LoadGraph(GraphPath(graph_arg), BinDirs());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn-launch: %s\n", e.what());
    return 2;
  }
  if (!run_dir_flag.empty()) graph.run_dir = run_dir_flag;
  if (lcm_url.empty()) lcm_url = graph.lcm_url;
  std::error_code ec;
  fs::create_directories(graph.run_dir + "/logs", ec);
  if (ec) {
    std::fprintf(stderr, "cairn-launch: cannot create %s: %s\n", graph.run_dir.c_str(), ec.message().c_str());
    return 2;
  }
  {
    std::ifstream pid_file(graph.run_dir + "/launch.pid");
    int old = -1;
    if ((pid_file >> old) && old != getpid() && Alive(old)) {
      std::fprintf(stderr, "cairn-launch: graph '%s' already runs (launcher pid %d); use 'down' first\n",
                   graph.name.c_str(), old);
      return 2;
    }
  }
  fs::remove(graph.run_dir + "/status.json", ec);
  if (detach) {
    const pid_t pid = fork();
    if (pid < 0) return 2;
    if (pid > 0) {
      std::printf("graph '%s' starting in the background (launcher pid %d); run dir %s\n",
                  graph.name.c_str(), pid, graph.run_dir.c_str());
      return 0;
    }
    setsid();
    const std::string log = graph.run_dir + "/launch.log";
    if (!freopen(log.c_str(), "a", stdout) || !freopen(log.c_str(), "a", stderr)) _exit(2);
    if (!freopen("/dev/null", "r", stdin)) _exit(2);
  }
  {
    std::ofstream pid_file(graph.run_dir + "/launch.pid", std::ios::trunc);
    pid_file << getpid() << "\n";
  }
  try {
    runtime::NodeOptions options;
    options.process_name = "cairn-launch";
    options.lcm_url = lcm_url;
    options.follow_sim_clock = false;
    runtime::Node node(options);
    launch::PosixRunner runner(graph.run_dir + "/logs", node.url());
    launch::Supervisor supervisor(graph, &runner, [&node](const std::string& line) {
      node.Event("%s", line.c_str());
    });
    launch::LaunchService service(&node, &supervisor, &runner, graph.run_dir + "/status.json");
    const int code = service.Run();
    fs::remove(graph.run_dir + "/launch.pid", ec);
    return code;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn-launch: %s\n", e.what());
    return 2;
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string lcm_url, run_dir;
  bool detach = false;
  double timeout_s = 60.0;
  common::FlagParser flags("cairn-launch COMMAND [GRAPH]", kSummary);
  flags.AddString("lcm-url", &lcm_url, "LCM bus for the graph (else the graph's lcm_url, LCM_DEFAULT_URL)");
  flags.AddString("run-dir", &run_dir, "run directory (default var/run/<graph>)");
  flags.AddBool("detach", &detach, "up: run in the background");
  flags.AddDouble("timeout", &timeout_s, "wait/down: seconds to wait");
  const int parsed = flags.Parse(argc, argv);
  if (parsed >= 0) return parsed;
  const auto& pos = flags.positional();
  if (pos.empty()) {
    std::fputs(flags.Usage().c_str(), stderr);
    return 2;
  }
  const std::string command = pos[0];
  const std::string graph_arg = pos.size() > 1 ? pos[1] : "";
  common::SetLogTag("cairn-launch");
  if (command == "up") {
    if (graph_arg.empty()) {
      std::fprintf(stderr, "cairn-launch: up needs a GRAPH\n");
      return 2;
    }
    return CmdUp(graph_arg, lcm_url, run_dir, detach);
  }
  if (command == "check") {
    try {
      const auto graph = launch::LoadGraph(GraphPath(graph_arg), BinDirs());
      std::printf("graph '%s' is valid; start order:", graph.name.c_str());
      for (const auto& name : graph.StartOrder()) std::printf(" %s", name.c_str());
      std::printf("\n");
      return 0;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "cairn-launch: %s\n", e.what());
      return 2;
    }
  }
  if (graph_arg.empty() && run_dir.empty()) {
    std::fprintf(stderr, "cairn-launch: %s needs a GRAPH or --run-dir\n", command.c_str());
    return 2;
  }
  const std::string dir = RunDirFor(graph_arg, run_dir);
  if (command == "status") return CmdStatus(dir);
  if (command == "wait") return CmdWait(dir, timeout_s);
  if (command == "down") return CmdDown(dir, timeout_s);
  std::fprintf(stderr, "cairn-launch: unknown command '%s' (see --help)\n", command.c_str());
  return 2;
}
