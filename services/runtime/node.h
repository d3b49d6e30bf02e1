#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "cairn/lcmt_health.hpp"
#include "common/log.h"

/// @file
/// Node: the LCM runtime every cairn process is built on.
///
/// - The bus URL comes from --lcm-url, else LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0.
///   A udpm URL without ttl gets ttl=0, so traffic never leaves the host by accident.
/// - Handlers are wrapped: a message that does not decode (truncated, foreign fingerprint) or a
///   handler that throws is counted and logged (rate-limited). Nothing unwinds into liblcm.
/// - A heartbeat goes out on HEALTH at 1 Hz: process, robot, pid, state, uptime, per-channel
///   counts and rates, decode errors and process counters.
/// - SIGINT/SIGTERM make Spin() return; the process then cleans up and exits.

namespace cairn::runtime {

inline constexpr char kDefaultLcmUrl[] = "udpm://239.255.76.67:7667?ttl=0";

/// `url` with a receive buffer of `bytes` when it is udpm:// and names none (a recv_buf_size it
/// names is kept); the kernel caps it at net.core.rmem_max. Processes that take bursts (a
/// mapper's tiles, the map store's saves, the simulator beside its own lidar) ask for one: with
/// the kernel's default (about 208 KB) a busy host drops datagrams, a request among them.
std::string WithReceiveBuffer(const std::string& url, int64_t bytes);
/// The receive buffer those processes ask for.
inline constexpr int64_t kLargeReceiveBufferBytes = 4 * 1024 * 1024;

/// Resolves the bus URL from a flag value and the environment, and enforces ttl=0 on udpm URLs
/// that do not state a ttl. @throws std::invalid_argument for an unsupported provider.
std::string ResolveLcmUrl(const std::string& flag_value);

struct NodeOptions {
  std::string process_name;  ///< "cairn-sim"
  std::string robot;         ///< empty for fleet processes
  std::string lcm_url;       ///< passed through ResolveLcmUrl
  double heartbeat_period_s{1.0};
  bool install_signal_handlers{true};
  bool follow_sim_clock{true};  ///< track SIM.CLOCK for sim_utime()
};

enum class HealthState : int8_t {
  kStarting = cairn::lcmt_health::STATE_STARTING,
  kReady = cairn::lcmt_health::STATE_READY,
  kDegraded = cairn::lcmt_health::STATE_DEGRADED,
  kStopping = cairn::lcmt_health::STATE_STOPPING,
};

/// Per-channel counters kept by the node.
struct ChannelCounters {
  int64_t messages{0};
  int64_t bytes{0};
  int64_t decode_errors{0};
  int64_t handler_errors{0};
  std::deque<std::pair<double, int64_t>> history;  ///< (time_s, messages) at heartbeats
  double rate_hz{0.0};
};

namespace internal {
/// The calling thread's encoding buffer for Node::Publish, at least `size` bytes: grown when
/// needed, never zeroed (encode() writes every byte; a lidar publishes 100 range images of
/// 17 KB per simulated second).
uint8_t* PublishBuffer(size_t size);
}  // namespace internal

class Node {
 public:
  /// @throws std::runtime_error if LCM cannot be created on the URL.
  explicit Node(NodeOptions options);
  ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  lcm::LCM& lcm() { return *lcm_; }
  const NodeOptions& options() const { return options_; }
  const std::string& url() const { return options_.lcm_url; }

  /// Subscribes a typed handler. Decode failures and exceptions are counted, never propagated.
  template <typename Msg>
  void Subscribe(const std::string& channel, std::function<void(const Msg&)> handler);
  /// Subscribes to raw bytes (channel regex); used by the spy and the recorder.
  void SubscribeRaw(const std::string& channel_regex,
                    std::function<void(const std::string& channel, const void* data, int size,
                                       int64_t recv_utime)>
                        handler);

  /// Encodes and publishes; counts bytes. Returns false (and logs, rate-limited) on failure.
  template <typename Msg>
  bool Publish(const std::string& channel, const Msg& msg);
  /// Publishes a batch (tiles of a layer), pausing pause_ms after every `burst` messages so a
  /// receiver's socket buffer can drain (burst <= 0 or pause_ms <= 0: no pauses).
  template <typename Msg>
  void PublishPaced(const std::string& channel, const std::vector<Msg>& messages, int burst,
                    double pause_ms);

  /// A wall-clock timer run from Spin(); the first call is one period after Spin starts.
  void AddTimer(double period_s, std::function<void()> callback);

  /// Runs until Stop() or a signal. Returns 0.
  int Spin();
  /// Handles messages for at most timeout_ms and runs due timers (also while stopping, so a
  /// process can drain). Returns false once Stop() was called or a signal arrived.
  bool SpinOnce(int timeout_ms);
  void Stop();
  bool stopping() const;

  /// Health reporting.
  void SetState(HealthState state, const std::string& message = "");
  HealthState state() const { return state_; }
  /// Logs a notable event at INFO and keeps it as the heartbeat's message.
  void Event(const char* format, ...) __attribute__((format(printf, 2, 3)));
  /// Logs a warning (rate-limited per key) and keeps it as the heartbeat's message.
  void Warn(const std::string& key, const std::string& message);
  /// Adds to a named counter reported in HEALTH (bad inputs, clamps, ...).
  void Count(const std::string& counter, int64_t increment = 1);
  /// Counts an input refused as bad (NaN, out of range, unknown profile): HEALTH dropped_inputs.
  void CountDropped(const std::string& counter, int64_t increment = 1);
  int64_t counter(const std::string& name) const;

  int64_t decode_errors() const { return decode_errors_; }
  int64_t handler_errors() const { return handler_errors_; }
  /// Last SIM.CLOCK time seen (0 when none), microseconds.
  int64_t sim_utime() const { return sim_utime_; }
  /// Sim time when a simulator runs, else wall time, microseconds.
  int64_t NowUtime() const;
  static int64_t WallUtime();
  /// Microseconds of a monotonic clock (for timeouts that must not follow a clock on the bus).
  static int64_t SteadyUtime();
  double uptime_s() const;

  /// Builds (and publishes, from the heartbeat timer) the health message.
  cairn::lcmt_health MakeHealth();
  void PublishHealth();

 private:
  void RecordIn(const std::string& channel, int size);
  void RecordDecodeError(const std::string& channel, int size);
  void RecordHandlerError(const std::string& channel, const std::string& what);
  void RecordOut(const std::string& channel, int size);
  void RunTimers();

  struct Timer {
    double period_s;
    std::chrono::steady_clock::time_point next;
    std::function<void()> callback;
  };

  NodeOptions options_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::chrono::steady_clock::time_point start_;
  std::atomic<bool> stop_{false};
  HealthState state_{HealthState::kStarting};
  std::string last_event_;
  mutable std::mutex mutex_;
  std::map<std::string, ChannelCounters> in_;
  std::map<std::string, ChannelCounters> out_;
  std::map<std::string, int64_t> counters_;
  std::map<std::string, std::unique_ptr<common::RateLimiter>> limiters_;
  int64_t decode_errors_{0};
  int64_t handler_errors_{0};
  int64_t dropped_inputs_{0};
  std::atomic<int64_t> sim_utime_{0};
  std::vector<Timer> timers_;
  // Keeps the handler closures alive for the lifetime of their subscriptions.
  std::vector<std::unique_ptr<std::function<void(const lcm::ReceiveBuffer*, const std::string&)>>>
      handlers_;
};

template <typename Msg>
void Node::Subscribe(const std::string& channel, std::function<void(const Msg&)> handler) {
  SubscribeRaw(channel, [this, handler](const std::string& ch, const void* data, int size,
                                        int64_t) {
    Msg msg;
    if (msg.decode(data, 0, size) < 0) {
      RecordDecodeError(ch, size);
      return;
    }
    try {
      handler(msg);
    } catch (const std::exception& e) {
      RecordHandlerError(ch, e.what());
    } catch (...) {
      RecordHandlerError(ch, "unknown exception");
    }
  });
}

template <typename Msg>
bool Node::Publish(const std::string& channel, const Msg& msg) {
  const int size = msg.getEncodedSize();
  if (size < 0) {
    Warn("publish:" + channel, "could not encode a message for " + channel);
    return false;
  }
  uint8_t* const buffer = internal::PublishBuffer(static_cast<size_t>(size));
  if (msg.encode(buffer, 0, size) < 0 || lcm_->publish(channel, buffer, size) != 0) {
    Warn("publish:" + channel, "could not publish on " + channel);
    return false;
  }
  RecordOut(channel, size);
  return true;
}

/// True once SIGINT or SIGTERM arrived (after Node installed its handlers).
bool ShutdownRequested();
/// Installs SIGINT/SIGTERM handlers that set ShutdownRequested() (idempotent).
void InstallSignalHandlers();

template <typename Msg>
void Node::PublishPaced(const std::string& channel, const std::vector<Msg>& messages, int burst,
                        double pause_ms) {
  int in_burst = 0;
  for (const auto& m : messages) {
    Publish(channel, m);
    if (++in_burst >= burst && burst > 0 && pause_ms > 0) {
      in_burst = 0;
      std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(pause_ms));
    }
  }
}

}  // namespace cairn::runtime
