#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/yaml_reader.h"

/// @file
/// A service graph for cairn-launch: processes, their dependencies, readiness and restart
/// policies, loaded strictly from YAML (config/graphs/*.yaml). Validation happens before
/// anything starts: an unknown key, a dependency cycle, an unknown dependency or a missing
/// executable is refused, naming the file and line.

namespace cairn::launch {

enum class RestartPolicy { kNever, kOnFailure, kAlways };
const char* RestartPolicyName(RestartPolicy policy);

/// What "ready" means for a process: working, not merely alive.
struct Readiness {
  /// Its HEALTH heartbeat arrived with state READY.
  bool heartbeat{true};
  /// Or: this channel is publishing at >= min_rate_hz (empty = unused).
  std::string channel;
  double min_rate_hz{0.0};
  double timeout_s{60.0};
};

struct ProcessSpec {
  std::string name;
  std::string command;  ///< as written
  std::string executable;  ///< resolved absolute path
  std::vector<std::string> args;
  std::map<std::string, std::string> env;
  std::string robot;
  std::vector<std::string> depends_on;
  Readiness ready;
  RestartPolicy restart{RestartPolicy::kOnFailure};
  double backoff_s{0.5};       ///< first restart delay; doubles per restart
  double max_backoff_s{10.0};
  int max_restarts{5};
  int stop_signal{15};         ///< SIGTERM
  double grace_s{5.0};         ///< then SIGKILL
  bool required{true};         ///< failing for good stops the graph
  /// Liveness after ready: a process whose readiness is its heartbeat and that sends none for
  /// this long (or whose ready channel stays below min_rate_hz this long) is hung: it is sent
  /// stop_signal, SIGKILL after grace_s, and restarted per its policy. 0 turns it off.
  double liveness_timeout_s{10.0};
  /// A process ready this long since its last start has its back-off and its count towards
  /// max_restarts reset (the status still counts every restart). 0: never reset.
  double reset_restarts_after_s{60.0};
  /// Expected publishing rates of channels this process owns (for cairn-spy and status).
  std::map<std::string, double> expected_rates_hz;
  int line{0};                 ///< line in the graph file, for messages
};

struct GraphSpec {
  std::string name;
  std::string file;
  std::string lcm_url;  ///< empty: inherit LCM_DEFAULT_URL / --lcm-url
  std::string run_dir;  ///< default var/run/<name>
  /// Each process's log is rotated when it passes this size: <name>.log is copied to
  /// <name>.log.1 (older copies shift up to <name>.log.<log_keep>, the oldest dropped) and
  /// truncated in place, so the process keeps writing to the same file. 0: no rotation.
  double log_max_mb{16.0};
  int log_keep{3};
  std::vector<ProcessSpec> processes;  ///< in file order

  const ProcessSpec* Find(const std::string& name) const;
  /// Processes in an order where every dependency comes first.
  std::vector<std::string> StartOrder() const;
  /// All expected channel rates of the graph.
  std::map<std::string, double> ExpectedRates() const;
};

/// How a command is resolved to an executable: an absolute path; a path with '/' relative to
/// the working directory or the graph file's folder; a bare name in `bin_dirs`, in order
/// (cairn-launch passes its own folder, then the folders of PATH: SearchDirs in commands.h).
/// Returns nullopt when nothing executable is found.
std::optional<std::string> ResolveExecutable(const std::string& command,
                                             const std::string& graph_dir,
                                             const std::vector<std::string>& bin_dirs);

/// Loads and validates a graph. @throws common::ConfigError naming file and line.
/// With require_executables false, commands are not resolved (readers such as cairn-spy that
/// only want the expected rates).
GraphSpec LoadGraph(const std::string& path, const std::vector<std::string>& bin_dirs,
                    bool require_executables = true);
GraphSpec LoadGraphString(const std::string& yaml, const std::string& where,
                          const std::vector<std::string>& bin_dirs,
                          bool require_executables = true);

/// Parses "SIGTERM", "TERM", "15", "SIGINT". @throws std::invalid_argument.
int ParseSignal(const std::string& text);

}  // namespace cairn::launch
