#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <string>

#include "services/runtime/channel_meter.h"

/// @file
/// cairn-spy's model: every channel on the bus with its decoded type (looked up by the 64-bit
/// fingerprint at the start of each message among the generated cairn types), rate, bandwidth,
/// decode errors and the age of the last message, against expected rates from a graph file.

namespace cairn::spy {

struct ChannelView {
  std::string channel;
  std::string type;  ///< "cairn.lcmt_pose", or "? (fingerprint 0x...)"
  runtime::ChannelRate rate;
  int64_t decode_errors{0};
  double expected_hz{0.0};  ///< 0 when the graph does not name the channel
  bool slow{false};         ///< below 80 % of the expected rate (or never seen)
};

/// How fast simulated time ran against the wall over the spy's window, read from SIM.CLOCK.
/// Expected rates in a graph file are in simulated time: when the simulator runs slower than real
/// time, a channel arrives that much slower on the wall clock and is not slow for it.
struct SimPace {
  bool known{false};
  double real_time_factor{1.0};  ///< simulated seconds per wall second
};

class Spy {
 public:
  /// window_s: the sliding window over which rates are measured.
  explicit Spy(std::map<std::string, double> expected_rates_hz = {}, double window_s = 3.0);
  /// Records one message (bytes as received).
  void OnMessage(const std::string& channel, const void* data, int size, double now_s);
  std::map<std::string, ChannelView> Snapshot(double now_s);
  /// The simulator's pace over the window (unknown without SIM.CLOCK traffic).
  SimPace Pace(double now_s);
  /// The table printed by cairn-spy.
  std::string Format(double now_s);

 private:
  void TrimClock(double now_s);

  runtime::ChannelMeter meter_;
  double window_s_;
  std::deque<std::pair<double, double>> clock_;  ///< (wall s, sim s) of SIM.CLOCK messages
  std::map<std::string, std::string> types_;
  std::map<std::string, int64_t> decode_errors_;
  std::map<std::string, double> expected_;
};

/// Type name for a fingerprint (nullptr when unknown).
const char* TypeForFingerprint(int64_t fingerprint);

}  // namespace cairn::spy
