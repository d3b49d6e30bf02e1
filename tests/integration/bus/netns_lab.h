#pragma once

// A small site network made of Linux network namespaces, for integration tests of the bus across
// hosts: every "host" is a namespace with its loopback up and one veth port ("eth0") into a
// switch namespace that holds a Linux bridge. Nothing is created in the caller's namespace; the
// names carry the test's pid, and the destructor deletes every namespace (their veth pairs go
// with them). Faults are nftables rules on the bridge's forward hook, inside the switch
// namespace: random loss (`numgen random mod 100 < N drop`) and a cut (drop everything).
//
// LCM multicast with ttl=1 leaves a host only through its eth0 (each host routes 224.0.0.0/4
// there) and never leaves the switch: the bus of the test stays inside its own namespaces.

#include <cstdint>
#include <string>
#include <vector>

namespace cairn::testing {

class NetnsLab {
 public:
  /// Why namespaces cannot be made here (not root, no `ip`, no `nft`, no bridge), or "" when
  /// they can. Probes by making (and deleting) one namespace.
  static std::string WhyUnavailable();

  /// Creates the switch namespace (bridge br0, multicast snooping off). `mtu` is the MTU of the
  /// bridge and every port. @throws std::runtime_error when a command fails.
  explicit NetnsLab(int mtu = 1500);
  /// Deletes every namespace made (the processes inside must have been stopped first).
  ~NetnsLab();
  NetnsLab(const NetnsLab&) = delete;
  NetnsLab& operator=(const NetnsLab&) = delete;

  /// Adds a host namespace joined to the bridge, address 10.213.0.<index>/24; returns its name.
  std::string AddHost(const std::string& label, int index);
  /// argv prefix running a command inside a host: {ip, netns, exec, <ns>}.
  std::vector<std::string> Exec(const std::string& ns) const;

  /// Drops `percent` % of the frames the bridge forwards (each copy of a flooded frame on its
  /// own); 0 removes the rule.
  void SetLoss(int percent);
  /// Drops every frame the bridge forwards while `cut` holds.
  void SetCut(bool cut);

  /// Sets a (namespaced) sysctl inside a host, e.g. "net.ipv4.ipfrag_time", "1".
  void Sysctl(const std::string& ns, const std::string& key, const std::string& value);
  /// A counter of a host's /proc/net/snmp ("Ip", "ReasmFails"); -1 when it cannot be read.
  int64_t Snmp(const std::string& ns, const std::string& group, const std::string& name) const;

  const std::string& switch_ns() const { return switch_ns_; }

 private:
  void Nft(const std::string& script);

  std::string prefix_;
  std::string switch_ns_;
  int mtu_;
  std::vector<std::string> namespaces_;  // made so far, the switch first
  bool loss_{false};
  bool cut_{false};
};

/// Switches the calling thread into a network namespace until destroyed: sockets made meanwhile
/// (an lcm::LCM with its subscriptions) belong to that namespace for good.
class NetnsScope {
 public:
  /// @throws std::runtime_error when the namespace cannot be entered.
  explicit NetnsScope(const std::string& ns);
  ~NetnsScope();
  NetnsScope(const NetnsScope&) = delete;
  NetnsScope& operator=(const NetnsScope&) = delete;

 private:
  int original_fd_{-1};
};

/// Runs a command (no shell) and returns its exit code; its output goes to `output` when given.
int RunCommand(const std::vector<std::string>& argv, std::string* output = nullptr);

/// The path of an executable found in the usual system folders, or "" (ip and nft live in
/// /usr/sbin, which is not on every user's PATH).
std::string SystemTool(const std::string& name);

}  // namespace cairn::testing
