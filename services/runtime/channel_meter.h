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
  /// Channel names come from the bus: at most max_channels are told apart; messages on any
  /// further channel are metered together as kOtherChannels, so a peer inventing names cannot
  /// grow the table (or the work of Rates) without bound.
  static constexpr char kOtherChannels[] = "(other channels)";
  static constexpr size_t kDefaultMaxChannels = 4096;
  explicit ChannelMeter(double window_s = 3.0, size_t max_channels = kDefaultMaxChannels)
      : window_s_(window_s), max_channels_(max_channels) {}
  void Record(const std::string& channel, int bytes, double now_s);
  /// Messages metered as kOtherChannels because the table was full.
  int64_t overflow_messages() const { return overflow_messages_; }
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
  size_t max_channels_;
  int64_t overflow_messages_{0};
  std::map<std::string, Entry> channels_;
};

}  // namespace cairn::runtime
