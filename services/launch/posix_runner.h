#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "services/launch/supervisor.h"

/// @file
/// Real processes for the supervisor: fork/exec in a process group of their own, output appended
/// to <run_dir>/logs/<name>.log, LCM_DEFAULT_URL set to the graph's bus. A child dies with the
/// launcher: it is sent SIGTERM when the launcher's thread that started it ends, however the
/// launcher ended (PR_SET_PDEATHSIG), and never runs on once the launcher is gone.

namespace cairn::launch {

class PosixRunner : public ProcessRunner {
 public:
  /// @param log_dir folder for per-process logs (created); @param lcm_url given to children.
  PosixRunner(std::string log_dir, std::string lcm_url);
  pid_t Spawn(const ProcessSpec& spec, std::string* error) override;
  void Signal(pid_t pid, int signal) override;
  std::optional<int> Poll(pid_t pid) override;
  pid_t GroupOf(pid_t pid) override;

  std::string LogPath(const std::string& name) const override {
    return log_dir_ + "/" + name + ".log";
  }

 private:
  std::string log_dir_;
  std::string lcm_url_;
};

/// Rotates `path` when it is larger than max_bytes: path.<keep-1> moves to path.<keep> (the
/// oldest is dropped), ..., path.1 to path.2, then path is copied to path.1 and truncated in
/// place. The process writing it (O_APPEND) goes on writing at the start of the same file;
/// what it writes between the end of the copy and the truncation (microseconds) is lost, as
/// with logrotate's copytruncate. Returns the size rotated, nullopt when the file is missing or
/// small enough, or when it failed (*error says why, and the log is left as it was).
std::optional<std::uintmax_t> RotateLog(const std::string& path, std::uintmax_t max_bytes,
                                        int keep, std::string* error);

/// CPU use and resident memory of a pid, from /proc.
struct ProcSample {
  double cpu_percent{0.0};
  double rss_mb{0.0};
};

/// Keeps the previous CPU tick count per pid to turn /proc counters into a percentage.
class ProcSampler {
 public:
  ProcSample Sample(pid_t pid, double now_s);

 private:
  std::map<pid_t, std::pair<double, long long>> last_;  // pid -> (time, ticks)
};

}  // namespace cairn::launch
