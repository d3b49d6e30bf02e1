#include "services/spy/lcm/spy.h"

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "cairn/lcmt_sim_clock.hpp"

#include "cairn/lcmtypes_registry.hpp"

namespace cairn::spy {
namespace {

int64_t ReadFingerprint(const void* data, int size) {
  if (size < 8) return 0;
  const auto* b = static_cast<const uint8_t*>(data);
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | b[i];
  return static_cast<int64_t>(v);
}

const cairn::LcmTypeInfo* FindType(int64_t fingerprint) {
  for (const auto& t : cairn::AllLcmTypes()) {
    if (t.fingerprint == fingerprint) return &t;
  }
  return nullptr;
}

std::string HumanBytes(double bps) {
  char buf[32];
  if (bps >= 1e6) {
    std::snprintf(buf, sizeof(buf), "%.2f MB/s", bps / 1e6);
  } else if (bps >= 1e3) {
    std::snprintf(buf, sizeof(buf), "%.1f kB/s", bps / 1e3);
  } else {
    std::snprintf(buf, sizeof(buf), "%.0f B/s", bps);
  }
  return buf;
}

}  // namespace

const char* TypeForFingerprint(int64_t fingerprint) {
  const auto* t = FindType(fingerprint);
  return t ? t->name : nullptr;
}

constexpr char kClockChannel[] = "SIM.CLOCK";

Spy::Spy(std::map<std::string, double> expected_rates_hz, double window_s)
    : meter_(window_s), window_s_(window_s), expected_(std::move(expected_rates_hz)) {}

// At most this many clock samples are kept in the window (a flood of SIM.CLOCK drops the oldest).
constexpr size_t kMaxClockSamples = 10000;

void Spy::TrimClock(double now_s) {
  while (!clock_.empty() && clock_.front().first < now_s - window_s_) clock_.pop_front();
  while (clock_.size() > kMaxClockSamples) clock_.pop_front();
}

SimPace Spy::Pace(double now_s) {
  TrimClock(now_s);
  SimPace pace;
  if (clock_.size() < 2) return pace;
  const double wall_s = clock_.back().first - clock_.front().first;
  const double sim_s = clock_.back().second - clock_.front().second;
  // Half a window of clock traffic at least, and time that moved forwards.
  if (wall_s < 0.5 * window_s_ || sim_s <= 0.0) return pace;
  pace.known = true;
  pace.real_time_factor = sim_s / wall_s;
  return pace;
}

void Spy::OnMessage(const std::string& channel, const void* data, int size, double now_s) {
  meter_.Record(channel, size, now_s);
  const int64_t fp = ReadFingerprint(data, size);
  const auto* type = FindType(fp);
  if (type == nullptr) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "? (fingerprint 0x%016llx)",
                  static_cast<unsigned long long>(fp));
    if (types_.count(channel) == 0) types_[channel] = buf;
    ++decode_errors_[channel];
    return;
  }
  // The clock is decoded once, into its type, for the simulator's pace; the rest only checked.
  const bool clock_message = channel == kClockChannel && fp == cairn::lcmt_sim_clock::getHash();
  cairn::lcmt_sim_clock clock;
  if ((clock_message ? clock.decode(data, 0, size) : type->decode(data, size)) < 0) {
    ++decode_errors_[channel];
    if (types_.count(channel) == 0) types_[channel] = type->name;
    return;
  }
  types_[channel] = type->name;
  if (clock_message && !clock.paused) {
    if (!clock_.empty() && clock.utime * 1e-6 < clock_.back().second) clock_.clear();  // restart
    clock_.emplace_back(now_s, clock.utime * 1e-6);
    TrimClock(now_s);
  }
}

std::map<std::string, ChannelView> Spy::Snapshot(double now_s) {
  std::map<std::string, ChannelView> views;
  for (const auto& [channel, rate] : meter_.Rates(now_s)) {
    ChannelView v;
    v.channel = channel;
    v.type = types_[channel];
    v.rate = rate;
    v.decode_errors = decode_errors_[channel];
    views[channel] = v;
  }
  // Expected rates are in simulated time; a simulator slower than real time delivers them that
  // much slower on the wall clock. A faster one is not given credit.
  const SimPace pace = Pace(now_s);
  const double pace_factor = pace.known ? std::min(1.0, pace.real_time_factor) : 1.0;
  for (const auto& [channel, hz] : expected_) {
    ChannelView& v = views[channel];
    v.channel = channel;
    if (v.type.empty()) v.type = "(not seen)";
    v.expected_hz = hz;
    v.slow = v.rate.rate_hz < 0.8 * hz * pace_factor;
  }
  return views;
}

std::string Spy::Format(double now_s) {
  std::ostringstream out;
  char line[512];
  std::snprintf(line, sizeof(line), "%-28s %-30s %9s %12s %7s %8s %s\n", "CHANNEL", "TYPE", "MSG/S",
                "BANDWIDTH", "ERRORS", "AGE(s)", "EXPECTED");
  out << line;
  int slow = 0;
  const SimPace pace = Pace(now_s);
  if (pace.known) {
    std::snprintf(line, sizeof(line), "simulated time at %.2fx real time%s\n",
                  pace.real_time_factor,
                  pace.real_time_factor < 1.0 ? " (expected rates judged at that pace)" : "");
    out << line;
  }
  for (const auto& [channel, v] : Snapshot(now_s)) {
    std::string expected;
    if (v.expected_hz > 0) {
      char b[64];
      std::snprintf(b, sizeof(b), "%.1f Hz%s", v.expected_hz, v.slow ? "  << SLOW" : "");
      expected = b;
      slow += v.slow;
    }
    char age[16] = "-";
    if (v.rate.messages > 0) std::snprintf(age, sizeof(age), "%.1f", v.rate.last_age_s);
    std::snprintf(line, sizeof(line), "%-28s %-30s %9.1f %12s %7lld %8s %s\n", channel.c_str(),
                  v.type.c_str(), v.rate.rate_hz, HumanBytes(v.rate.bandwidth_Bps).c_str(),
                  static_cast<long long>(v.decode_errors), age, expected.c_str());
    out << line;
  }
  if (slow > 0) out << slow << " channel(s) below their expected rate\n";
  return out.str();
}

}  // namespace cairn::spy
