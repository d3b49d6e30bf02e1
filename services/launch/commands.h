#pragma once

#include <optional>
#include <string>
#include <vector>

#include "services/launch/graph.h"

/// @file
/// The commands of cairn-launch that work on a run directory without the bus: status, wait,
/// down, check, and the preparation of `up` (run directory, pid file, detaching). Each returns
/// the process exit code it documents and prints what went wrong on stderr.

namespace cairn::launch {

/// Where bare command names of a graph are looked up: the folder of the running executable
/// (where the other cairn executables are), then the folders of `path_list` (PATH's syntax:
/// folders separated by ':'; main passes the environment's PATH).
std::vector<std::string> SearchDirs(const std::string& path_list);
/// A graph argument as a file: the path itself when it exists, else config/graphs/<arg>.yaml
/// when that exists, else the argument unchanged (LoadGraph then says what is wrong).
std::string GraphPath(const std::string& graph_arg);
/// The run directory of a graph: the flag when given, else the graph's own, else
/// var/run/<stem of the argument>.
std::string RunDirFor(const std::string& graph_arg, const std::string& run_dir_flag,
                      const std::vector<std::string>& search_dirs);
/// True while `pid` runs; a zombie (exited, not yet reaped by its parent) counts as gone.
bool ProcessAlive(int pid);

/// Prints the process table of a run directory. 0, or 1 when there is no readable status.
int CmdStatus(const std::string& run_dir);
/// Waits until the graph is ready (0), failed or stopped (1), or timeout_s passed (2).
int CmdWait(const std::string& run_dir, double timeout_s);
/// Stops a running graph (SIGTERM to its launcher) and waits for it. When no launcher runs, the
/// processes its status file lists are killed. 0 when stopped, 1 when the launcher had to be
/// killed after timeout_s.
int CmdDown(const std::string& run_dir, double timeout_s);
/// Validates a graph and prints its start order. 0, or 2 for an invalid graph.
int CmdCheck(const std::string& graph_arg, const std::vector<std::string>& search_dirs);

/// What `up` runs once it is prepared.
struct UpPlan {
  GraphSpec graph;
  std::string lcm_url;  ///< the flag, else the graph's
};
/// Prepares `up`: loads the graph, makes its run directory, refuses a graph that already runs,
/// and with `detach` forks (the parent returns `*exit_code` 0 and no plan; the child continues
/// in a new session with its output in <run_dir>/launch.log). Writes the pid file.
/// No plan and `*exit_code` 2 on an error.
std::optional<UpPlan> PrepareUp(const std::string& graph_arg, const std::string& lcm_url,
                                const std::string& run_dir_flag, bool detach,
                                const std::vector<std::string>& search_dirs, int* exit_code);
/// Removes the pid file `up` wrote.
void FinishUp(const UpPlan& plan);

}  // namespace cairn::launch
