#include "services/runtime/node.h"

#include <algorithm>
#include <csignal>
#include <cstdarg>
#include <cstdlib>
#include <stdexcept>

#include <sys/time.h>
#include <unistd.h>

#include "cairn/lcmt_sim_clock.hpp"

#include "common/channels.h"

namespace cairn::runtime {

namespace internal {
uint8_t* PublishBuffer(size_t size) {
  thread_local std::unique_ptr<uint8_t[]> buffer;
  thread_local size_t capacity = 0;
  if (size > capacity) {
    capacity = std::max(size, 2 * capacity);
    buffer.reset(new uint8_t[capacity]);
  }
  return buffer.get();
}
}  // namespace internal
namespace {

std::atomic<bool> g_shutdown{false};

void HandleSignal(int) { g_shutdown = true; }

double SteadySeconds(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(t.time_since_epoch()).count();
}

}  // namespace

bool ShutdownRequested() { return g_shutdown.load(); }

void InstallSignalHandlers() {
  struct sigaction action {};
  action.sa_handler = HandleSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: a blocking poll returns at once
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
}

std::string ResolveLcmUrl(const std::string& flag_value) {
  std::string url = flag_value;
  if (url.empty()) {
    const char* env = std::getenv("LCM_DEFAULT_URL");
    if (env != nullptr && env[0] != '\0') url = env;
  }
  if (url.empty()) url = kDefaultLcmUrl;
  const auto scheme_end = url.find("://");
  if (scheme_end == std::string::npos) {
    throw std::invalid_argument("LCM URL '" + url +
                                "' has no provider (udpm://, memq://, file://)");
  }
  const std::string scheme = url.substr(0, scheme_end);
  if (scheme != "udpm" && scheme != "memq" && scheme != "file" && scheme != "tcpq" &&
      scheme != "mpudpm") {
    throw std::invalid_argument("LCM URL '" + url + "': unsupported provider '" + scheme + "'");
  }
  if (scheme == "udpm" && url.find("ttl=") == std::string::npos) {
    url += (url.find('?') == std::string::npos ? "?ttl=0" : "&ttl=0");
  }
  return url;
}

std::string WithReceiveBuffer(const std::string& url, int64_t bytes) {
  if (url.rfind("udpm://", 0) != 0 || url.find("recv_buf_size=") != std::string::npos) return url;
  return url + (url.find('?') == std::string::npos ? "?" : "&") +
         "recv_buf_size=" + std::to_string(bytes);
}

Node::Node(NodeOptions options) : options_(std::move(options)) {
  options_.lcm_url = ResolveLcmUrl(options_.lcm_url);
  start_ = std::chrono::steady_clock::now();
  if (options_.install_signal_handlers) InstallSignalHandlers();
  const std::string tag = options_.robot.empty()
                              ? options_.process_name
                              : options_.process_name + "[" + options_.robot + "]";
  common::SetLogTag(tag);
  if (const char* level = std::getenv("CAIRN_LOG_LEVEL")) {
    if (auto parsed = common::LogLevelFromName(level)) common::SetLogLevel(*parsed);
  }
  lcm_ = std::make_unique<lcm::LCM>(options_.lcm_url);
  if (!lcm_->good()) {
    throw std::runtime_error("cannot open the LCM bus at " + options_.lcm_url +
                             " (is multicast enabled on the loopback interface?)");
  }
  if (options_.follow_sim_clock) {
    Subscribe<cairn::lcmt_sim_clock>(
        channels::kSimClock, [this](const cairn::lcmt_sim_clock& c) { sim_utime_ = c.utime; });
  }
  if (options_.heartbeat_period_s > 0) {
    AddTimer(options_.heartbeat_period_s, [this] { PublishHealth(); });
  }
}

Node::~Node() = default;

void Node::SubscribeRaw(
    const std::string& channel_regex,
    std::function<void(const std::string&, const void*, int, int64_t)> handler) {
  auto closure =
      std::make_unique<std::function<void(const lcm::ReceiveBuffer*, const std::string&)>>(
          [this, handler](const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
            RecordIn(channel, static_cast<int>(rbuf->data_size));
            try {
              handler(channel, rbuf->data, static_cast<int>(rbuf->data_size), rbuf->recv_utime);
            } catch (const std::exception& e) {
              RecordHandlerError(channel, e.what());
            } catch (...) {
              RecordHandlerError(channel, "unknown exception");
            }
          });
  auto* fn = closure.get();
  lcm_->subscribeFunction<std::function<void(const lcm::ReceiveBuffer*, const std::string&)>*>(
      channel_regex,
      [](const lcm::ReceiveBuffer* rbuf, const std::string& channel,
         std::function<void(const lcm::ReceiveBuffer*, const std::string&)>* f) {
        (*f)(rbuf, channel);
      },
      fn);
  handlers_.push_back(std::move(closure));
}

void Node::AddTimer(double period_s, std::function<void()> callback) {
  const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(period_s));
  timers_.push_back({period_s, std::chrono::steady_clock::now() + period, std::move(callback)});
}

void Node::RunTimers() {
  const auto now = std::chrono::steady_clock::now();
  for (auto& timer : timers_) {
    if (now < timer.next) continue;
    const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(timer.period_s));
    timer.next += period;
    if (timer.next < now) timer.next = now + period;  // do not burst after a stall
    try {
      timer.callback();
    } catch (const std::exception& e) {
      RecordHandlerError("<timer>", e.what());
    }
  }
}

bool Node::SpinOnce(int timeout_ms) {
  // Wait no longer than the next timer.
  auto now = std::chrono::steady_clock::now();
  int wait_ms = timeout_ms;
  for (const auto& timer : timers_) {
    // Round up, so the wait never ends just before a timer is due (a busy spin).
    const auto until_us =
        std::chrono::duration_cast<std::chrono::microseconds>(timer.next - now).count();
    const int until = static_cast<int>((until_us + 999) / 1000);
    wait_ms = std::max(0, std::min(wait_ms, until));
  }
  lcm_->handleTimeout(wait_ms);
  RunTimers();
  return !stopping();
}

int Node::Spin() {
  while (SpinOnce(100)) {
  }
  if (state_ != HealthState::kStopping) SetState(HealthState::kStopping, "shutting down");
  PublishHealth();
  return 0;
}

void Node::Stop() { stop_ = true; }

bool Node::stopping() const { return stop_ || ShutdownRequested(); }

void Node::SetState(HealthState state, const std::string& message) {
  const bool changed = state != state_;
  state_ = state;
  if (!message.empty()) {
    std::lock_guard<std::mutex> lock(mutex_);
    last_event_ = message;
  }
  if (changed) {
    static const char* kNames[] = {"starting", "ready", "degraded", "stopping"};
    CAIRN_LOG_INFO("state %s%s%s", kNames[static_cast<int>(state)], message.empty() ? "" : ": ",
                   message.c_str());
    PublishHealth();
  }
}

void Node::Event(const char* format, ...) {
  char text[1024];
  va_list args;
  va_start(args, format);
  std::vsnprintf(text, sizeof(text), format, args);
  va_end(args);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    last_event_ = text;
  }
  CAIRN_LOG_INFO("%s", text);
}

void Node::Warn(const std::string& key, const std::string& message) {
  common::RateLimiter* limiter;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    last_event_ = message;
    auto& slot = limiters_[key];
    if (!slot) slot = std::make_unique<common::RateLimiter>(5.0);
    limiter = slot.get();
  }
  int64_t suppressed = 0;
  if (limiter->Allow(&suppressed)) {
    if (suppressed > 0) {
      CAIRN_LOG_WARN("%s (and %lld more like it)", message.c_str(),
                     static_cast<long long>(suppressed));
    } else {
      CAIRN_LOG_WARN("%s", message.c_str());
    }
  }
}

void Node::Count(const std::string& counter, int64_t increment) {
  std::lock_guard<std::mutex> lock(mutex_);
  counters_[counter] += increment;
}

void Node::CountDropped(const std::string& counter, int64_t increment) {
  std::lock_guard<std::mutex> lock(mutex_);
  counters_[counter] += increment;
  dropped_inputs_ += increment;
}

int64_t Node::counter(const std::string& name) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = counters_.find(name);
  return it == counters_.end() ? 0 : it->second;
}

void Node::RecordIn(const std::string& channel, int size) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto& c = in_[channel];
  ++c.messages;
  c.bytes += size;
}

void Node::RecordOut(const std::string& channel, int size) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto& c = out_[channel];
  ++c.messages;
  c.bytes += size;
}

void Node::RecordDecodeError(const std::string& channel, int size) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++in_[channel].decode_errors;
    ++decode_errors_;
  }
  Warn("decode:" + channel, "dropped a message on " + channel + " that does not decode (" +
                                std::to_string(size) + " bytes: truncated or a foreign type)");
}

void Node::RecordHandlerError(const std::string& channel, const std::string& what) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (in_.count(channel)) ++in_[channel].handler_errors;
    ++handler_errors_;
  }
  Warn("handler:" + channel, "handler for " + channel + " failed: " + what);
}

int64_t Node::WallUtime() {
  timeval tv{};
  gettimeofday(&tv, nullptr);
  return static_cast<int64_t>(tv.tv_sec) * 1000000 + tv.tv_usec;
}

int64_t Node::SteadyUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

int64_t Node::NowUtime() const {
  const int64_t sim = sim_utime_;
  return sim > 0 ? sim : WallUtime();
}

double Node::uptime_s() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

cairn::lcmt_health Node::MakeHealth() {
  cairn::lcmt_health h{};
  h.utime = WallUtime();
  h.sim_utime = sim_utime_;
  h.process = options_.process_name;
  h.robot = options_.robot;
  h.pid = static_cast<int32_t>(getpid());
  h.state = static_cast<int8_t>(state_);
  h.uptime_s = uptime_s();
  const double now_s = SteadySeconds(std::chrono::steady_clock::now());
  std::lock_guard<std::mutex> lock(mutex_);
  h.decode_errors = decode_errors_;
  h.handler_errors = handler_errors_;
  h.dropped_inputs = dropped_inputs_;
  h.message = last_event_;
  auto add = [&](std::map<std::string, ChannelCounters>& table, bool outgoing) {
    for (auto& [name, c] : table) {
      // Rate over a window of up to 5 heartbeats.
      c.history.emplace_back(now_s, c.messages);
      while (c.history.size() > 6) c.history.pop_front();
      const auto& first = c.history.front();
      const double dt = now_s - first.first;
      c.rate_hz = dt > 0.2 ? (c.messages - first.second) / dt : 0.0;
      cairn::lcmt_channel_stats s{};
      s.channel = name;
      s.outgoing = outgoing;
      s.messages = c.messages;
      s.bytes = c.bytes;
      s.rate_hz = c.rate_hz;
      s.decode_errors = c.decode_errors;
      s.handler_errors = c.handler_errors;
      h.channels.push_back(s);
    }
  };
  add(in_, false);
  add(out_, true);
  h.num_channels = static_cast<int32_t>(h.channels.size());
  for (const auto& [name, value] : counters_) {
    h.counter_names.push_back(name);
    h.counter_values.push_back(value);
  }
  h.num_counters = static_cast<int32_t>(h.counter_names.size());
  return h;
}

void Node::PublishHealth() {
  const cairn::lcmt_health h = MakeHealth();
  Publish(channels::kHealth, h);
}

}  // namespace cairn::runtime
