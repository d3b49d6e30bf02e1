#include "tests/support/harness.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cairn/lcmt_goal.hpp"
#include "cairn/lcmt_nav_status.hpp"
#include "common/channels.h"

namespace cairn::testing {
namespace fs = std::filesystem;

std::string PrivateLcmUrl() {
  // Ask the kernel for a free UDP port; the multicast group stays the product's default.
  int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  int port = 0;
  if (fd >= 0 && bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) == 0) {
    socklen_t len = sizeof(addr);
    getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
    port = ntohs(addr.sin_port);
  }
  if (fd >= 0) close(fd);
  if (port == 0) port = 20000 + (getpid() % 20000);
  return "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0";
}

std::string BinPath(const std::string& name) {
  return std::string(CAIRN_BINARY_DIR) + "/bin/" + name;
}

std::string SourcePath(const std::string& relative) {
  return std::string(CAIRN_SOURCE_DIR) + "/" + relative;
}

std::string MapperConfigWithoutOctomap(const std::string& dir) {
  std::stringstream text;
  text << std::ifstream(SourcePath("config/mapping/mapper.yaml")).rdbuf();
  std::string s = text.str();
  const std::string on = "octomap:\n  enabled: true";
  const auto at = s.find(on);
  if (at == std::string::npos)
    throw std::runtime_error(
        "config/mapping/mapper.yaml no longer has 'octomap:\n  enabled: true'");
  s.replace(at, on.size(), "octomap:\n  enabled: false");
  const std::string path = dir + "/mapper.yaml";
  std::ofstream(path) << s;
  return path;
}

std::string TestTempDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "test";
  for (auto& c : name) {
    if (c == '/') c = '_';
  }
  const fs::path dir = fs::path(CAIRN_BINARY_DIR) / "test-tmp" / name;
  std::error_code ec;
  fs::remove_all(dir, ec);
  fs::create_directories(dir);
  return dir.string();
}

ChildProcess::ChildProcess(std::vector<std::string> argv, std::vector<std::string> env,
                           std::string log_path)
    : name_(fs::path(argv.at(0)).filename().string()), log_path_(std::move(log_path)) {
  const int log_fd = open(log_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (log_fd < 0) throw std::runtime_error("cannot open " + log_path_);
  const pid_t parent = getpid();
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    setpgid(0, 0);
    // A test killed from outside (a ctest or shell timeout) never runs its destructors: the
    // children stop with it instead of running on and sharing the next run's directories.
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(1);
    dup2(log_fd, STDOUT_FILENO);
    dup2(log_fd, STDERR_FILENO);
    for (const auto& kv : env) putenv(const_cast<char*>(kv.c_str()));
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    execv(args[0], args.data());
    std::fprintf(stderr, "exec %s failed\n", args[0]);
    _exit(127);
  }
  setpgid(pid_, pid_);
  close(log_fd);
}

ChildProcess::~ChildProcess() {
  if (Running()) Stop(3.0);
}

bool ChildProcess::Running() {
  if (status_) return false;
  int status = 0;
  const pid_t r = waitpid(pid_, &status, WNOHANG);
  if (r == pid_) {
    status_ = status;
    return false;
  }
  return r == 0;
}

void ChildProcess::Signal(int sig) {
  if (Running()) kill(pid_, sig);
}

std::optional<int> ChildProcess::WaitExit(double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    if (!Running()) return status_;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (!Running()) return status_;
  return std::nullopt;
}

int ChildProcess::Stop(double grace_s) {
  if (!Running()) return status_.value_or(-1);
  kill(pid_, SIGTERM);
  if (auto s = WaitExit(grace_s)) return *s;
  kill(-pid_, SIGKILL);
  kill(pid_, SIGKILL);
  waitpid(pid_, nullptr, 0);
  status_ = -1;
  return -1;
}

std::string ChildProcess::Log() const {
  std::ifstream in(log_path_);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

ProcessSet::ProcessSet(std::string url) : url_(std::move(url)), dir_(TestTempDir()) {}

ProcessSet::ProcessSet(std::string url, std::string dir)
    : url_(std::move(url)), dir_(std::move(dir)) {
  std::filesystem::create_directories(dir_);
}

ProcessSet::~ProcessSet() {
  for (auto it = processes_.rbegin(); it != processes_.rend(); ++it) (*it)->Stop(5.0);
  if (::testing::Test::HasFailure()) PrintLogs();
}

ChildProcess& ProcessSet::Start(const std::string& exe, std::vector<std::string> args,
                                std::vector<std::string> env) {
  std::vector<std::string> argv = {BinPath(exe)};
  argv.insert(argv.end(), args.begin(), args.end());
  argv.push_back("--lcm-url");
  argv.push_back(url_);
  return StartRaw(exe, std::move(argv), std::move(env));
}

ChildProcess& ProcessSet::StartRaw(const std::string& label, std::vector<std::string> argv,
                                   std::vector<std::string> env) {
  const std::string log = dir_ + "/" + label + "." + std::to_string(processes_.size()) + ".log";
  processes_.push_back(std::make_unique<ChildProcess>(std::move(argv), std::move(env), log));
  return *processes_.back();
}

std::string TailOfFile(const std::string& path, int lines) {
  std::ifstream in(path);
  std::deque<std::string> tail;
  std::string line;
  while (std::getline(in, line)) {
    tail.push_back(line);
    if (static_cast<int>(tail.size()) > lines) tail.pop_front();
  }
  std::string out;
  for (const auto& l : tail) out += l + "\n";
  return out;
}

void ProcessSet::PrintLogs() const {
  for (const auto& p : processes_) {
    std::fprintf(stderr, "\n===== log of %s (pid %d, %s) =====\n%s", p->name().c_str(), p->pid(),
                 p->log_path().c_str(), p->Log().c_str());
  }
  for (const auto& dir : log_dirs_) {
    std::error_code ec;
    std::vector<std::filesystem::path> files;
    for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
      if (entry.path().extension() == ".log") files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    for (const auto& file : files) {
      std::ifstream in(file);
      std::stringstream ss;
      ss << in.rdbuf();
      std::fprintf(stderr, "\n===== %s =====\n%s", file.c_str(), ss.str().c_str());
    }
  }
  std::fflush(stderr);
}

bool WaitFor(const std::function<bool()>& condition, double timeout_s,
             const std::function<void()>& pump) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    if (pump) {
      pump();
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  return condition();
}

namespace {
// The test's bus takes every channel (lidar slices, tiles): a large receive buffer keeps a
// reply from being dropped behind a burst (the kernel caps it at net.core.rmem_max).
std::string WithLargeReceiveBuffer(const std::string& url) {
  if (url.rfind("udpm://", 0) != 0 || url.find("recv_buf_size=") != std::string::npos) return url;
  return url + (url.find('?') == std::string::npos ? "?" : "&") + "recv_buf_size=4194304";
}
}  // namespace

Bus::Bus(const std::string& url) : lcm_(WithLargeReceiveBuffer(url)) {
  if (!lcm_.good()) throw std::runtime_error("cannot open LCM at " + url);
  lcm_.subscribeFunction<Bus*>(
      ".*",
      [](const lcm::ReceiveBuffer* rbuf, const std::string& channel, Bus* self) {
        const auto* bytes = static_cast<const uint8_t*>(rbuf->data);
        std::vector<uint8_t> data(bytes, bytes + rbuf->data_size);
        ++self->counts_[channel];
        if (channel == "HEALTH") {
          cairn::lcmt_health h;
          if (h.decode(data.data(), 0, static_cast<int>(data.size())) >= 0) {
            self->health_[h.process + "|" + h.robot] = h;
            self->health_[h.process + "|*"] = h;
          }
        }
        auto kept = self->keep_.find(channel);
        if (kept != self->keep_.end()) kept->second.push_back(data);
        self->last_[channel] = std::move(data);
      },
      this);
}

void Bus::Pump(int timeout_ms) { lcm_.handleTimeout(timeout_ms); }

int64_t Bus::Count(const std::string& channel) const {
  auto it = counts_.find(channel);
  return it == counts_.end() ? 0 : it->second;
}

std::optional<cairn::lcmt_health> Bus::Health(const std::string& process,
                                              const std::string& robot) const {
  auto it = health_.find(process + "|" + (robot.empty() ? "*" : robot));
  if (it == health_.end()) return std::nullopt;
  return it->second;
}

bool SendPoseGoal(Bus& bus, const std::string& robot, int64_t goal_id, double x_m, double y_m,
                  double timeout_s, const std::function<void()>& pump) {
  cairn::lcmt_goal goal{};
  goal.robot = robot;
  goal.goal_id = goal_id;
  goal.kind = cairn::lcmt_goal::KIND_POSE;
  goal.x_m = x_m;
  goal.y_m = y_m;
  const std::string status_channel = channels::ForRobot(robot, channels::kNavStatus);
  const std::string goal_channel = channels::ForRobot(robot, channels::kGoal);
  auto last_sent = std::chrono::steady_clock::now() - std::chrono::seconds(2);
  return WaitFor(
      [&] {
        const auto status = bus.Last<cairn::lcmt_nav_status>(status_channel);
        if (status && status->goal_id == goal_id) return true;
        if (std::chrono::steady_clock::now() - last_sent > std::chrono::seconds(1)) {
          bus.Publish(goal_channel, goal);
          last_sent = std::chrono::steady_clock::now();
        }
        return false;
      },
      timeout_s, pump ? pump : std::function<void()>([&] { bus.Pump(20); }));
}

}  // namespace cairn::testing
