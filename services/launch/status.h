#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

/// @file
/// The launcher's status file (<run_dir>/status.json), rewritten atomically every second, which
/// `cairn-launch status` and `cairn-launch wait` read. JSON, so other tools can read it too.

namespace cairn::launch {

struct ProcessRow {
  std::string name;
  std::string robot;
  std::string state;
  int pid{-1};
  int restarts{0};
  double cpu_percent{0.0};
  double rss_mb{0.0};
  double uptime_s{0.0};
  std::string last_exit;
  std::string log;
  /// Outgoing channel rates from the process's own heartbeat.
  std::map<std::string, double> channels_hz;
};

struct GraphStatus {
  std::string graph;
  std::string file;
  std::string lcm_url;
  int launcher_pid{-1};
  std::string state;  ///< "starting", "ready", "stopping", "stopped", "failed"
  std::string message;
  double updated_unix_s{0.0};
  std::vector<ProcessRow> processes;
  std::map<std::string, double> channel_rates_hz;    ///< measured by the launcher
  std::map<std::string, double> expected_rates_hz;   ///< from the graph
};

std::string ToJson(const GraphStatus& status);
/// @returns nullopt (with *error) if the text is not a status document.
std::optional<GraphStatus> ParseStatus(const std::string& json, std::string* error);
/// Writes atomically (temporary file + rename).
bool WriteStatusFile(const std::string& path, const GraphStatus& status);
std::optional<GraphStatus> ReadStatusFile(const std::string& path, std::string* error);
/// The row of the named process, nullptr if the graph has none.
const ProcessRow* FindProcess(const GraphStatus& status, const std::string& name);
/// The table printed by `cairn-launch status`.
std::string FormatStatusTable(const GraphStatus& status);

}  // namespace cairn::launch
