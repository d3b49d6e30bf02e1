// cairn-launch: starts a service graph from YAML, watches it, restarts, captures output.

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "common/flags.h"
#include "common/log.h"
#include "services/launch/commands.h"
#include "services/launch/lcm/launch_service.h"

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

int Up(const std::string& graph_arg, const std::string& lcm_url, const std::string& run_dir,
       bool detach, const std::vector<std::string>& search_dirs) {
  namespace launch = cairn::launch;
  if (graph_arg.empty()) {
    std::fprintf(stderr, "cairn-launch: up needs a GRAPH\n");
    return 2;
  }
  int exit_code = 2;
  const auto plan = launch::PrepareUp(graph_arg, lcm_url, run_dir, detach, search_dirs, &exit_code);
  if (!plan) return exit_code;
  const int code = launch::RunGraph(plan->graph, plan->lcm_url);
  launch::FinishUp(*plan);
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  namespace launch = cairn::launch;
  std::string lcm_url, run_dir;
  bool detach = false;
  double timeout_s = 60.0;
  cairn::common::FlagParser flags("cairn-launch COMMAND [GRAPH]", kSummary);
  flags.AddString("lcm-url", &lcm_url,
                  "LCM bus for the graph (else the graph's lcm_url, LCM_DEFAULT_URL)");
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
  cairn::common::SetLogTag("cairn-launch");
  if (const char* level = std::getenv("CAIRN_LOG_LEVEL")) {
    if (auto parsed = cairn::common::LogLevelFromName(level)) cairn::common::SetLogLevel(*parsed);
  }
  const char* path_env = std::getenv("PATH");
  const std::vector<std::string> search_dirs = launch::SearchDirs(path_env ? path_env : "");
  if (command == "up") return Up(graph_arg, lcm_url, run_dir, detach, search_dirs);
  if (command == "check") return launch::CmdCheck(graph_arg, search_dirs);
  if (graph_arg.empty() && run_dir.empty()) {
    std::fprintf(stderr, "cairn-launch: %s needs a GRAPH or --run-dir\n", command.c_str());
    return 2;
  }
  const std::string dir = launch::RunDirFor(graph_arg, run_dir, search_dirs);
  if (command == "status") return launch::CmdStatus(dir);
  if (command == "wait") return launch::CmdWait(dir, timeout_s);
  if (command == "down") return launch::CmdDown(dir, timeout_s);
  std::fprintf(stderr, "cairn-launch: unknown command '%s' (see --help)\n", command.c_str());
  return 2;
}
