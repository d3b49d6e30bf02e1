#include "services/launch/graph.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <set>
#include <sstream>

#include <signal.h>
#include <unistd.h>

namespace cairn::launch {
namespace fs = std::filesystem;
using common::ConfigError;
using common::YamlMap;

const char* RestartPolicyName(RestartPolicy policy) {
  switch (policy) {
    case RestartPolicy::kNever:
      return "never";
    case RestartPolicy::kOnFailure:
      return "on-failure";
    case RestartPolicy::kAlways:
      return "always";
  }
  return "?";
}

int ParseSignal(const std::string& text) {
  static const std::map<std::string, int> kSignals = {
      {"TERM", SIGTERM}, {"INT", SIGINT},   {"KILL", SIGKILL}, {"HUP", SIGHUP},
      {"QUIT", SIGQUIT}, {"USR1", SIGUSR1}, {"USR2", SIGUSR2}};
  std::string name = text;
  if (name.rfind("SIG", 0) == 0) name = name.substr(3);
  auto it = kSignals.find(name);
  if (it != kSignals.end()) return it->second;
  char* end = nullptr;
  const long n = std::strtol(text.c_str(), &end, 10);
  if (end != text.c_str() && *end == '\0' && n > 0 && n < 65) return static_cast<int>(n);
  throw std::invalid_argument("unknown signal '" + text + "'");
}

const ProcessSpec* GraphSpec::Find(const std::string& name) const {
  for (const auto& p : processes) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

std::vector<std::string> GraphSpec::StartOrder() const {
  std::vector<std::string> order;
  std::set<std::string> done;
  std::function<void(const ProcessSpec&)> visit = [&](const ProcessSpec& p) {
    if (done.count(p.name)) return;
    done.insert(p.name);
    for (const auto& dep : p.depends_on) visit(*Find(dep));
    order.push_back(p.name);
  };
  for (const auto& p : processes) visit(p);
  return order;
}

std::map<std::string, double> GraphSpec::ExpectedRates() const {
  std::map<std::string, double> rates;
  for (const auto& p : processes) {
    for (const auto& [channel, hz] : p.expected_rates_hz) rates[channel] = hz;
  }
  return rates;
}

namespace {

// "a, b and 2 more folders" for an error message.
std::string SearchedText(const std::vector<std::string>& dirs) {
  if (dirs.empty()) return "no folder: give it as a path";
  std::string text = dirs[0];
  if (dirs.size() > 1) text += ", " + dirs[1];
  if (dirs.size() > 2) text += " and " + std::to_string(dirs.size() - 2) + " more folders";
  return text;
}

}  // namespace

std::optional<std::string> ResolveExecutable(const std::string& command,
                                             const std::string& graph_dir,
                                             const std::vector<std::string>& bin_dirs) {
  auto executable = [](const fs::path& p) {
    std::error_code ec;
    return fs::is_regular_file(p, ec) && access(p.c_str(), X_OK) == 0;
  };
  if (command.empty()) return std::nullopt;
  const fs::path cmd(command);
  if (cmd.is_absolute()) {
    if (executable(cmd)) return cmd.string();
    return std::nullopt;
  }
  if (command.find('/') != std::string::npos) {
    for (const fs::path& base : {fs::current_path(), fs::path(graph_dir)}) {
      const fs::path p = base / cmd;
      if (executable(p)) return fs::absolute(p).lexically_normal().string();
    }
    return std::nullopt;
  }
  for (const auto& dir : bin_dirs) {
    const fs::path p = fs::path(dir) / cmd;
    if (executable(p)) return fs::absolute(p).lexically_normal().string();
  }
  return std::nullopt;
}

namespace {

bool ValidName(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
  });
}

ProcessSpec LoadProcess(YamlMap& map, const std::string& name, const std::string& graph_dir,
                        const std::vector<std::string>& bin_dirs, bool require_executables) {
  ProcessSpec p;
  p.name = name;
  p.line = 0;
  const YAML::Node where = map.Raw("command");
  p.command = map.Require<std::string>("command");
  map.Get("args", &p.args);
  if (map.Has("env")) {
    YamlMap env = map.Child("env");
    for (const auto& key : env.Keys()) p.env[key] = env.Require<std::string>(key);
  }
  map.Get("robot", &p.robot);
  map.Get("depends_on", &p.depends_on);
  if (map.Has("ready")) {
    YamlMap ready = map.Child("ready");
    ready.Get("heartbeat", &p.ready.heartbeat);
    ready.Get("channel", &p.ready.channel);
    ready.Get("min_rate_hz", &p.ready.min_rate_hz);
    ready.Get("timeout_s", &p.ready.timeout_s);
    if (!p.ready.channel.empty()) {
      if (!ready.Has("heartbeat")) p.ready.heartbeat = false;
      if (p.ready.min_rate_hz <= 0.0) {
        ready.Fail(ready.Raw("channel"),
                   "process '" + name + "': ready.channel needs min_rate_hz > 0");
      }
    }
    ready.Finish();
  }
  std::string restart = "on-failure";
  map.Get("restart", &restart);
  if (restart == "never") {
    p.restart = RestartPolicy::kNever;
  } else if (restart == "on-failure") {
    p.restart = RestartPolicy::kOnFailure;
  } else if (restart == "always") {
    p.restart = RestartPolicy::kAlways;
  } else {
    map.Fail(map.Raw("restart"),
             "process '" + name + "': restart must be never, on-failure or always");
  }
  map.Get("backoff_s", &p.backoff_s);
  map.Get("max_backoff_s", &p.max_backoff_s);
  map.Get("max_restarts", &p.max_restarts);
  std::string stop_signal = "SIGTERM";
  if (map.Get("stop_signal", &stop_signal)) {
    try {
      p.stop_signal = ParseSignal(stop_signal);
    } catch (const std::invalid_argument& e) {
      map.Fail(map.Raw("stop_signal"), e.what());
    }
  }
  map.Get("grace_s", &p.grace_s);
  map.Get("required", &p.required);
  map.Get("liveness_timeout_s", &p.liveness_timeout_s);
  map.Get("reset_restarts_after_s", &p.reset_restarts_after_s);
  if (map.Has("expected_rates_hz")) {
    YamlMap rates = map.Child("expected_rates_hz");
    for (const auto& key : rates.Keys()) p.expected_rates_hz[key] = rates.Require<double>(key);
  }
  map.Finish();
  if (p.backoff_s < 0 || p.max_backoff_s < p.backoff_s || p.max_restarts < 0 || p.grace_s < 0) {
    map.Fail(where, "process '" + name +
                        "': backoff_s, max_backoff_s, max_restarts and grace_s must be >= 0");
  }
  if (!(p.liveness_timeout_s >= 0) || !(p.reset_restarts_after_s >= 0)) {
    map.Fail(where, "process '" + name +
                        "': liveness_timeout_s and reset_restarts_after_s must be >= 0 (0 = off)");
  }
  const auto exe = require_executables ? ResolveExecutable(p.command, graph_dir, bin_dirs)
                                       : std::optional<std::string>(p.command);
  if (!exe) {
    map.Fail(where, "process '" + name + "': executable '" + p.command + "' not found (looked in " +
                        SearchedText(bin_dirs) + ")");
  }
  p.executable = *exe;
  p.line = where.Mark().line + 1;
  return p;
}

GraphSpec LoadFromMap(YamlMap root, const std::string& file,
                      const std::vector<std::string>& bin_dirs, bool require_executables) {
  GraphSpec graph;
  graph.file = file;
  const std::string graph_dir = fs::path(file).parent_path().string();
  graph.name = fs::path(file).stem().string();
  root.Get("name", &graph.name);
  if (!ValidName(graph.name))
    root.Fail(root.Raw("name"), "graph name '" + graph.name + "' is not a valid name");
  root.Get("lcm_url", &graph.lcm_url);
  root.Get("run_dir", &graph.run_dir);
  if (graph.run_dir.empty()) graph.run_dir = "var/run/" + graph.name;
  root.Get("log_max_mb", &graph.log_max_mb);
  root.Get("log_keep", &graph.log_keep);
  if (!(graph.log_max_mb >= 0) || graph.log_keep < 1 || graph.log_keep > 100) {
    root.Fail(root.Raw(root.Has("log_keep") ? "log_keep" : "log_max_mb"),
              "log_max_mb must be >= 0 (0 = no rotation) and log_keep between 1 and 100");
  }
  if (!root.Has("processes")) root.Fail(YAML::Node(), "graph has no 'processes'");
  YAML::Node processes = root.Raw("processes");
  if (!processes.IsMap()) root.Fail(processes, "'processes' must be a map of name -> process");
  for (const auto& kv : processes) {
    const std::string name = root.As<std::string>(kv.first, "a process name");
    if (!ValidName(name)) root.Fail(kv.first, "process name '" + name + "' is not a valid name");
    YamlMap pm = root.Wrap(kv.second, "processes." + name);
    graph.processes.push_back(LoadProcess(pm, name, graph_dir, bin_dirs, require_executables));
    graph.processes.back().line = kv.first.Mark().line + 1;
  }
  root.Finish();
  if (graph.processes.empty()) throw ConfigError(file + ": graph has no processes");
  // Unknown dependencies.
  for (const auto& p : graph.processes) {
    for (const auto& dep : p.depends_on) {
      if (graph.Find(dep) == nullptr) {
        throw ConfigError(file + ":" + std::to_string(p.line) + ": process '" + p.name +
                          "' depends on unknown process '" + dep + "'");
      }
      if (dep == p.name) {
        throw ConfigError(file + ":" + std::to_string(p.line) + ": process '" + p.name +
                          "' depends on itself");
      }
    }
  }
  // Cycles (depth-first search with colours).
  std::map<std::string, int> colour;
  std::vector<std::string> stack;
  std::function<void(const ProcessSpec&)> visit = [&](const ProcessSpec& p) {
    colour[p.name] = 1;
    stack.push_back(p.name);
    for (const auto& dep : p.depends_on) {
      if (colour[dep] == 1) {
        std::string cycle;
        auto it = std::find(stack.begin(), stack.end(), dep);
        for (; it != stack.end(); ++it) cycle += *it + " -> ";
        cycle += dep;
        throw ConfigError(file + ":" + std::to_string(p.line) + ": dependency cycle: " + cycle);
      }
      if (colour[dep] == 0) visit(*graph.Find(dep));
    }
    stack.pop_back();
    colour[p.name] = 2;
  };
  for (const auto& p : graph.processes) {
    if (colour[p.name] == 0) visit(p);
  }
  return graph;
}

}  // namespace

GraphSpec LoadGraph(const std::string& path, const std::vector<std::string>& bin_dirs,
                    bool require_executables) {
  return LoadFromMap(YamlMap::LoadFile(path), path, bin_dirs, require_executables);
}

GraphSpec LoadGraphString(const std::string& yaml, const std::string& where,
                          const std::vector<std::string>& bin_dirs, bool require_executables) {
  return LoadFromMap(YamlMap::FromString(yaml, where), where, bin_dirs, require_executables);
}

}  // namespace cairn::launch
