#pragma once

#include <deque>
#include <map>
#include <string>

/// @file
/// Per-channel message rate and bandwidth over a sliding window, for cairn-launch (readiness by
/// rate) and cairn-spy.

namespace cairn::runtime {

struct ChannelRate {
  int64_t messages{0};       ///< since the start
  int64_t bytes{0};
  double rate_hz{0.0};       ///< over the window
  double bandwidth_Bps{0.0};
  double last_age_s{-1.0};   ///< seconds since the last message
};

class ChannelMeter {
 public:
  explicit ChannelMeter(double window_s = 3.0) : window_s_(window_s) {}
  void Record(const std::string& channel, int bytes, double now_s);
  /// Rates of every channel seen, at time now_s.
  std::map<std::string, ChannelRate> Rates(double now_s);

 private:
  struct Entry {
    int64_t messages{0};
    int64_t bytes{0};
    double first_s{0.0};
    double last_s{0.0};
    std::deque<std::pair<double, int>> window;
  };
  void Trim(Entry& e, double now_s) const;
  double window_s_;
  std::map<std::string, Entry> channels_;
};

}  // namespace cairn::runtime
