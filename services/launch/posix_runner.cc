#include "services/launch/posix_runner.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

namespace cairn::launch {

PosixRunner::PosixRunner(std::string log_dir, std::string lcm_url)
    : log_dir_(std::move(log_dir)), lcm_url_(std::move(lcm_url)) {
  std::filesystem::create_directories(log_dir_);
}

pid_t PosixRunner::Spawn(const ProcessSpec& spec, std::string* error) {
  const std::string log_path = LogPath(spec.name);
  const int log_fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (log_fd < 0) {
    *error = "cannot open log " + log_path + ": " + std::strerror(errno);
    return -1;
  }
  {
    const std::time_t now = std::time(nullptr);
    char stamp[64];
    std::strftime(stamp, sizeof(stamp), "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
    const std::string banner = std::string("===== cairn-launch: starting ") + spec.name + " at " + stamp + " =====\n";
    (void)!write(log_fd, banner.data(), banner.size());
  }
  // A close-on-exec pipe reports exec failures synchronously.
  int pipe_fd[2];
  if (pipe2(pipe_fd, O_CLOEXEC) != 0) {
    close(log_fd);
    *error = std::string("pipe: ") + std::strerror(errno);
    return -1;
  }
  std::vector<std::string> argv_storage = {spec.executable};
  argv_storage.insert(argv_storage.end(), spec.args.begin(), spec.args.end());
  const pid_t launcher = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    close(log_fd);
    close(pipe_fd[0]);
    close(pipe_fd[1]);
    *error = std::string("fork: ") + std::strerror(errno);
    return -1;
  }
  if (pid == 0) {
    setpgid(0, 0);
    // Dies with the launcher: SIGTERM (a clean stop) when it goes, and at once if it went
    // between the fork and here.
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != launcher) _exit(1);
    // Children start with default signal dispositions and an empty mask.
    sigset_t all;
    sigemptyset(&all);
    sigprocmask(SIG_SETMASK, &all, nullptr);
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    signal(SIGPIPE, SIG_DFL);
    dup2(log_fd, STDOUT_FILENO);
    dup2(log_fd, STDERR_FILENO);
    const int devnull = open("/dev/null", O_RDONLY);
    if (devnull >= 0) dup2(devnull, STDIN_FILENO);
    if (!lcm_url_.empty()) setenv("LCM_DEFAULT_URL", lcm_url_.c_str(), 1);
    for (const auto& [key, value] : spec.env) setenv(key.c_str(), value.c_str(), 1);
    std::vector<char*> argv;
    for (auto& a : argv_storage) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    const int err = errno;
    (void)!write(pipe_fd[1], &err, sizeof(err));
    _exit(127);
  }
  setpgid(pid, pid);
  close(log_fd);
  close(pipe_fd[1]);
  int child_errno = 0;
  const ssize_t n = read(pipe_fd[0], &child_errno, sizeof(child_errno));
  close(pipe_fd[0]);
  if (n == sizeof(child_errno)) {
    waitpid(pid, nullptr, 0);
    *error = "exec " + spec.executable + ": " + std::strerror(child_errno);
    return -1;
  }
  return pid;
}

void PosixRunner::Signal(pid_t pid, int sig) {
  if (pid <= 0) return;
  kill(-pid, sig);  // its process group (the process and anything it spawned)
  kill(pid, sig);
}

pid_t PosixRunner::GroupOf(pid_t pid) {
  const pid_t group = getpgid(pid);
  return group < 0 ? -1 : group;
}

std::optional<int> PosixRunner::Poll(pid_t pid) {
  int status = 0;
  const pid_t r = waitpid(pid, &status, WNOHANG);
  if (r == pid) {
    kill(-pid, SIGKILL);  // leave no orphans of a dead process behind
    return status;
  }
  if (r < 0 && errno == ECHILD) return 0;
  return std::nullopt;
}

std::optional<std::uintmax_t> RotateLog(const std::string& path, std::uintmax_t max_bytes,
                                        int keep, std::string* error) {
  namespace fs = std::filesystem;
  error->clear();
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec || size <= max_bytes || keep < 1) return std::nullopt;
  auto numbered = [&](int i) { return path + "." + std::to_string(i); };
  for (int i = keep - 1; i >= 1; --i) {
    if (!fs::exists(numbered(i), ec)) continue;
    fs::rename(numbered(i), numbered(i + 1), ec);
    if (ec) {
      *error = "rename " + numbered(i) + ": " + ec.message();
      return std::nullopt;
    }
  }
  fs::copy_file(path, numbered(1), fs::copy_options::overwrite_existing, ec);
  if (ec) {
    *error = "copy to " + numbered(1) + ": " + ec.message();
    return std::nullopt;
  }
  if (truncate(path.c_str(), 0) != 0) {
    *error = "truncate: " + std::string(std::strerror(errno));
    return std::nullopt;
  }
  return size;
}

ProcSample ProcSampler::Sample(pid_t pid, double now_s) {
  ProcSample s;
  if (pid <= 0) return s;
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string content;
  std::getline(stat, content);
  const auto close_paren = content.rfind(')');
  if (close_paren != std::string::npos) {
    std::istringstream fields(content.substr(close_paren + 2));
    std::string field;
    long long utime = 0, stime = 0;
    for (int i = 3; i <= 15 && fields >> field; ++i) {
      if (i == 14) utime = std::stoll(field);
      if (i == 15) stime = std::stoll(field);
    }
    const long long ticks = utime + stime;
    auto it = last_.find(pid);
    if (it != last_.end() && now_s > it->second.first) {
      const double hz = static_cast<double>(sysconf(_SC_CLK_TCK));
      s.cpu_percent = 100.0 * (ticks - it->second.second) / hz / (now_s - it->second.first);
    }
    last_[pid] = {now_s, ticks};
  }
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) {
      s.rss_mb = std::stod(line.substr(6)) / 1024.0;
      break;
    }
  }
  return s;
}

}  // namespace cairn::launch
