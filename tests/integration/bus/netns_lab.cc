#include "tests/integration/bus/netns_lab.h"

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fcntl.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

namespace cairn::testing {
namespace {

constexpr char kPrefix[] = "cbus";

std::string Join(const std::vector<std::string>& argv) {
  std::string out;
  for (const auto& a : argv) out += (out.empty() ? "" : " ") + a;
  return out;
}

void Check(const std::vector<std::string>& argv) {
  std::string output;
  const int code = RunCommand(argv, &output);
  if (code != 0) {
    throw std::runtime_error("'" + Join(argv) + "' failed (" + std::to_string(code) +
                             "): " + output);
  }
}

// Namespaces of earlier runs killed before their destructor ran (a ctest timeout): their owner
// pid is gone. Processes inside died with their parent (the harness sets PR_SET_PDEATHSIG).
void DeleteOrphans(const std::string& ip) {
  std::string list;
  if (RunCommand({ip, "netns", "list"}, &list) != 0) return;
  std::istringstream lines(list);
  std::string line;
  while (std::getline(lines, line)) {
    const std::string name = line.substr(0, line.find(' '));
    if (name.rfind(kPrefix, 0) != 0) continue;
    const std::string rest = name.substr(std::strlen(kPrefix));
    const auto dash = rest.find('-');
    if (dash == std::string::npos || dash == 0) continue;
    const pid_t owner = static_cast<pid_t>(std::atol(rest.substr(0, dash).c_str()));
    if (owner > 0 && kill(owner, 0) != 0 && errno == ESRCH) {
      RunCommand({ip, "netns", "delete", name});
    }
  }
}

}  // namespace

int RunCommand(const std::vector<std::string>& argv, std::string* output) {
  int fds[2];
  if (pipe(fds) != 0) return -1;
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    return -1;
  }
  if (pid == 0) {
    dup2(fds[1], STDOUT_FILENO);
    dup2(fds[1], STDERR_FILENO);
    close(fds[0]);
    close(fds[1]);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    std::fprintf(stderr, "exec %s failed: %s\n", args[0], std::strerror(errno));
    _exit(127);
  }
  close(fds[1]);
  std::string text;
  char buf[4096];
  ssize_t n;
  while ((n = read(fds[0], buf, sizeof(buf))) > 0 || (n < 0 && errno == EINTR)) {
    if (n > 0) text.append(buf, static_cast<size_t>(n));
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (output != nullptr) *output = text;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string SystemTool(const std::string& name) {
  for (const char* dir : {"/usr/sbin/", "/sbin/", "/usr/bin/", "/bin/"}) {
    const std::string path = dir + name;
    if (access(path.c_str(), X_OK) == 0) return path;
  }
  return "";
}

std::string NetnsLab::WhyUnavailable() {
  if (geteuid() != 0) return "network namespaces need root (run the test as root)";
  const std::string ip = SystemTool("ip");
  if (ip.empty()) return "no 'ip' command (package iproute2)";
  if (SystemTool("nft").empty()) return "no 'nft' command (package nftables)";
  const std::string probe = std::string(kPrefix) + std::to_string(getpid()) + "-probe";
  std::string output;
  if (RunCommand({ip, "netns", "add", probe}, &output) != 0) {
    return "cannot make a network namespace: " + output;
  }
  std::string why;
  if (RunCommand({ip, "-n", probe, "link", "add", "br0", "type", "bridge"}, &output) != 0) {
    why = "cannot make a bridge in a network namespace: " + output;
  } else if (RunCommand({SystemTool("ip"), "netns", "exec", probe, SystemTool("nft"), "add",
                         "table", "bridge", "probe"},
                        &output) != 0) {
    why = "nftables cannot filter a bridge in a network namespace: " + output;
  }
  RunCommand({ip, "netns", "delete", probe});
  return why;
}

NetnsLab::NetnsLab(int mtu) : mtu_(mtu) {
  const std::string ip = SystemTool("ip");
  if (ip.empty()) throw std::runtime_error("no 'ip' command");
  DeleteOrphans(ip);
  prefix_ = std::string(kPrefix) + std::to_string(getpid()) + "-";
  switch_ns_ = prefix_ + "switch";
  Check({ip, "netns", "add", switch_ns_});
  namespaces_.push_back(switch_ns_);
  try {
    Check({ip, "-n", switch_ns_, "link", "set", "lo", "up"});
    // Snooping off: the bridge floods multicast to every port, like a plain switch; which host
    // listens is LCM's business (every process joins the group).
    Check({ip, "-n", switch_ns_, "link", "add", "br0", "mtu", std::to_string(mtu_), "type",
           "bridge", "mcast_snooping", "0"});
    Check({ip, "-n", switch_ns_, "link", "set", "br0", "up"});
  } catch (...) {
    RunCommand({ip, "netns", "delete", switch_ns_});  // no destructor runs for a failed constructor
    throw;
  }
}

NetnsLab::~NetnsLab() {
  const std::string ip = SystemTool("ip");
  // Hosts first (their veth pairs vanish with them), the switch last.
  for (auto it = namespaces_.rbegin(); it != namespaces_.rend(); ++it) {
    std::string output;
    if (RunCommand({ip, "netns", "delete", *it}, &output) != 0) {
      std::fprintf(stderr, "NetnsLab: could not delete namespace %s: %s\n", it->c_str(),
                   output.c_str());
    }
  }
}

std::string NetnsLab::AddHost(const std::string& label, int index) {
  const std::string ip = SystemTool("ip");
  const std::string ns = prefix_ + label;
  const std::string port = "p" + std::to_string(index);
  Check({ip, "netns", "add", ns});
  namespaces_.push_back(ns);
  Check({ip, "-n", ns, "link", "set", "lo", "up"});
  // The pair is made inside the host and its peer placed in the switch: nothing ever appears in
  // the test's own namespace.
  Check({ip, "-n", ns, "link", "add", "eth0", "mtu", std::to_string(mtu_), "type", "veth", "peer",
         "name", port, "mtu", std::to_string(mtu_), "netns", switch_ns_});
  Check({ip, "-n", switch_ns_, "link", "set", port, "master", "br0"});
  Check({ip, "-n", switch_ns_, "link", "set", port, "up"});
  Check({ip, "-n", ns, "addr", "add", "10.213.0." + std::to_string(index) + "/24", "dev", "eth0"});
  Check({ip, "-n", ns, "link", "set", "eth0", "up"});
  Check({ip, "-n", ns, "route", "add", "224.0.0.0/4", "dev", "eth0"});
  return ns;
}

std::vector<std::string> NetnsLab::Exec(const std::string& ns) const {
  return {SystemTool("ip"), "netns", "exec", ns};
}

void NetnsLab::Nft(const std::string& script) {
  std::vector<std::string> argv = Exec(switch_ns_);
  argv.push_back(SystemTool("nft"));
  std::istringstream words(script);
  std::string word;
  while (words >> word) argv.push_back(word);
  Check(argv);
}

void NetnsLab::SetLoss(int percent) {
  if (loss_) Nft("delete table bridge cairn_loss");
  loss_ = false;
  if (percent <= 0) return;
  Nft("add table bridge cairn_loss");
  Nft("add chain bridge cairn_loss forward { type filter hook forward priority 0 ; }");
  Nft("add rule bridge cairn_loss forward numgen random mod 100 < " + std::to_string(percent) +
      " drop");
  loss_ = true;
}

void NetnsLab::SetCut(bool cut) {
  if (cut == cut_) return;
  if (cut) {
    Nft("add table bridge cairn_cut");
    Nft("add chain bridge cairn_cut forward { type filter hook forward priority -10 ; policy drop "
        "; }");
  } else {
    Nft("delete table bridge cairn_cut");
  }
  cut_ = cut;
}

void NetnsLab::Sysctl(const std::string& ns, const std::string& key, const std::string& value) {
  // /proc/sys/net of the namespace: written from a thread inside it.
  std::string path = "/proc/sys/" + key;
  for (auto& c : path) {
    if (c == '.') c = '/';
  }
  NetnsScope in(ns);
  std::ofstream out(path);
  out << value << "\n";
  out.close();
  if (!out) throw std::runtime_error("cannot set " + key + " in " + ns);
}

int64_t NetnsLab::Snmp(const std::string& ns, const std::string& group,
                       const std::string& name) const {
  std::vector<std::string> argv = Exec(ns);
  argv.push_back(SystemTool("cat"));
  argv.push_back("/proc/net/snmp");
  std::string text;
  if (RunCommand(argv, &text) != 0) return -1;
  // Pairs of lines "<group>: names..." and "<group>: values...".
  std::istringstream lines(text);
  std::string header, values;
  while (std::getline(lines, header) && std::getline(lines, values)) {
    if (header.rfind(group + ":", 0) != 0) continue;
    std::istringstream h(header), v(values);
    std::string key, value;
    h >> key;
    v >> value;
    while (h >> key && v >> value) {
      if (key == name) return std::atoll(value.c_str());
    }
  }
  return -1;
}

NetnsScope::NetnsScope(const std::string& ns) {
  original_fd_ = open("/proc/thread-self/ns/net", O_RDONLY | O_CLOEXEC);
  if (original_fd_ < 0) throw std::runtime_error("cannot open this thread's network namespace");
  const std::string path = "/run/netns/" + ns;
  const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    close(original_fd_);
    throw std::runtime_error("cannot open " + path);
  }
  const int r = setns(fd, CLONE_NEWNET);
  const int error = errno;
  close(fd);
  if (r != 0) {
    close(original_fd_);
    throw std::runtime_error("cannot enter " + ns + ": " + std::strerror(error));
  }
}

NetnsScope::~NetnsScope() {
  if (setns(original_fd_, CLONE_NEWNET) != 0) {
    std::fprintf(stderr, "NetnsScope: cannot return to the original namespace: %s\n",
                 std::strerror(errno));
    std::abort();
  }
  close(original_fd_);
}

}  // namespace cairn::testing
