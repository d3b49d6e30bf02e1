#include "services/launch/status.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <yaml-cpp/yaml.h>

namespace cairn::launch {
namespace {

std::string Quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof(buf), "\\u%04x", c);
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

std::string Number(double v) {
  if (!std::isfinite(v)) return "0";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3f", v);
  return buf;
}

std::string RateMap(const std::map<std::string, double>& m) {
  std::string out = "{";
  bool first = true;
  for (const auto& [k, v] : m) {
    out += (first ? "" : ", ") + Quote(k) + ": " + Number(v);
    first = false;
  }
  return out + "}";
}

std::map<std::string, double> ReadRates(const YAML::Node& node) {
  std::map<std::string, double> m;
  if (node && node.IsMap()) {
    for (const auto& kv : node) m[kv.first.as<std::string>()] = kv.second.as<double>();
  }
  return m;
}

}  // namespace

std::string ToJson(const GraphStatus& s) {
  std::ostringstream out;
  out << "{\n  \"graph\": " << Quote(s.graph) << ",\n  \"file\": " << Quote(s.file)
      << ",\n  \"lcm_url\": " << Quote(s.lcm_url) << ",\n  \"launcher_pid\": " << s.launcher_pid
      << ",\n  \"state\": " << Quote(s.state) << ",\n  \"message\": " << Quote(s.message)
      << ",\n  \"updated_unix_s\": " << Number(s.updated_unix_s) << ",\n  \"processes\": [";
  for (size_t i = 0; i < s.processes.size(); ++i) {
    const ProcessRow& p = s.processes[i];
    out << (i ? "," : "") << "\n    {\"name\": " << Quote(p.name) << ", \"robot\": " << Quote(p.robot)
        << ", \"state\": " << Quote(p.state) << ", \"pid\": " << p.pid << ", \"restarts\": " << p.restarts
        << ", \"cpu_percent\": " << Number(p.cpu_percent) << ", \"rss_mb\": " << Number(p.rss_mb)
        << ", \"uptime_s\": " << Number(p.uptime_s) << ", \"last_exit\": " << Quote(p.last_exit)
        << ", \"log\": " << Quote(p.log) << ", \"channels_hz\": " << RateMap(p.channels_hz) << "}";
  }
  out << "\n  ],\n  \"channel_rates_hz\": " << RateMap(s.channel_rates_hz)
      << ",\n  \"expected_rates_hz\": " << RateMap(s.expected_rates_hz) << "\n}\n";
  return out.str();
}

std::optional<GraphStatus> ParseStatus(const std::string& json, std::string* error) {
  try {
    const YAML::Node root = YAML::Load(json);
    if (!root.IsMap() || !root["graph"] || !root["processes"]) {
      if (error) *error = "not a cairn-launch status document";
      return std::nullopt;
    }
    GraphStatus s;
    s.graph = root["graph"].as<std::string>();
    s.file = root["file"].as<std::string>("");
    s.lcm_url = root["lcm_url"].as<std::string>("");
    s.launcher_pid = root["launcher_pid"].as<int>(-1);
    s.state = root["state"].as<std::string>("");
    s.message = root["message"].as<std::string>("");
    s.updated_unix_s = root["updated_unix_s"].as<double>(0.0);
    for (const auto& p : root["processes"]) {
      ProcessRow row;
      row.name = p["name"].as<std::string>();
      row.robot = p["robot"].as<std::string>("");
      row.state = p["state"].as<std::string>("");
      row.pid = p["pid"].as<int>(-1);
      row.restarts = p["restarts"].as<int>(0);
      row.cpu_percent = p["cpu_percent"].as<double>(0.0);
      row.rss_mb = p["rss_mb"].as<double>(0.0);
      row.uptime_s = p["uptime_s"].as<double>(0.0);
      row.last_exit = p["last_exit"].as<std::string>("");
      row.log = p["log"].as<std::string>("");
      row.channels_hz = ReadRates(p["channels_hz"]);
      s.processes.push_back(row);
    }
    s.channel_rates_hz = ReadRates(root["channel_rates_hz"]);
    s.expected_rates_hz = ReadRates(root["expected_rates_hz"]);
    return s;
  } catch (const YAML::Exception& e) {
    if (error) *error = std::string("cannot parse status: ") + e.what();
    return std::nullopt;
  }
}

bool WriteStatusFile(const std::string& path, const GraphStatus& status) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) return false;
    out << ToJson(status);
    if (!out.good()) return false;
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  return !ec;
}

const ProcessRow* FindProcess(const GraphStatus& status, const std::string& name) {
  for (const auto& p : status.processes) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

std::optional<GraphStatus> ReadStatusFile(const std::string& path, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    if (error) *error = "no status file at " + path + " (is the graph running?)";
    return std::nullopt;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  return ParseStatus(ss.str(), error);
}

std::string FormatStatusTable(const GraphStatus& s) {
  std::ostringstream out;
  char line[512];
  std::snprintf(line, sizeof(line), "graph %s (%s) — %s%s%s\nbus %s, launcher pid %d\n\n", s.graph.c_str(),
                s.file.c_str(), s.state.c_str(), s.message.empty() ? "" : ": ", s.message.c_str(),
                s.lcm_url.c_str(), s.launcher_pid);
  out << line;
  std::snprintf(line, sizeof(line), "%-14s %-10s %-9s %8s %7s %9s %9s  %s\n", "PROCESS", "ROBOT", "STATE",
                "PID", "RESTART", "CPU%", "RSS(MB)", "CHANNELS (out Hz)");
  out << line;
  for (const auto& p : s.processes) {
    std::string chans;
    for (const auto& [c, hz] : p.channels_hz) {
      if (c == "HEALTH") continue;
      char b[128];
      std::snprintf(b, sizeof(b), "%s%s %.1f", chans.empty() ? "" : ", ", c.c_str(), hz);
      chans += b;
    }
    if (chans.empty() && !p.last_exit.empty()) chans = "last: " + p.last_exit;
    std::snprintf(line, sizeof(line), "%-14s %-10s %-9s %8d %7d %9.1f %9.1f  %s\n", p.name.c_str(),
                  p.robot.empty() ? "-" : p.robot.c_str(), p.state.c_str(), p.pid, p.restarts,
                  p.cpu_percent, p.rss_mb, chans.c_str());
    out << line;
  }
  if (!s.expected_rates_hz.empty()) {
    out << "\nexpected channel rates:\n";
    for (const auto& [c, want] : s.expected_rates_hz) {
      auto it = s.channel_rates_hz.find(c);
      const double have = it == s.channel_rates_hz.end() ? 0.0 : it->second;
      std::snprintf(line, sizeof(line), "  %-32s %8.1f Hz (expected %.1f)%s\n", c.c_str(), have, want,
                    have < 0.8 * want ? "  << SLOW" : "");
      out << line;
    }
  }
  return out.str();
}

}  // namespace cairn::launch
