#include "services/runtime/channel_meter.h"

#include <algorithm>

namespace cairn::runtime {

void ChannelMeter::Trim(Entry& e, double now_s) const {
  while (!e.window.empty() && e.window.front().first < now_s - window_s_) e.window.pop_front();
}

void ChannelMeter::Record(const std::string& channel, int bytes, double now_s) {
  auto it = channels_.find(channel);
  if (it == channels_.end()) {
    if (channels_.size() >= max_channels_) {
      ++overflow_messages_;
      it = channels_.try_emplace(kOtherChannels).first;
    } else {
      it = channels_.try_emplace(channel).first;
    }
  }
  Entry& e = it->second;
  if (e.messages == 0) e.first_s = now_s;
  ++e.messages;
  e.bytes += bytes;
  e.last_s = now_s;
  e.window.emplace_back(now_s, bytes);
  Trim(e, now_s);
}

std::map<std::string, ChannelRate> ChannelMeter::Rates(double now_s) {
  std::map<std::string, ChannelRate> out;
  for (auto& [name, e] : channels_) {
    Trim(e, now_s);
    ChannelRate r;
    r.messages = e.messages;
    r.bytes = e.bytes;
    // n messages in the window span n - 1 intervals between the first and the last. Time since
    // the last message counts only beyond one mean interval, so that a live channel reads its
    // true rate (not (n - 1) / window, which is low by 1 / window) and a channel that went quiet
    // decays towards zero.
    const size_t n = e.window.size();
    if (n >= 2) {
      const double seen_s = e.window.back().first - e.window.front().first;
      const double mean_dt = seen_s / static_cast<double>(n - 1);
      const double overdue_s = std::max(0.0, (now_s - e.window.back().first) - mean_dt);
      const double span = std::max(seen_s + overdue_s, 1e-6);
      int64_t bytes = 0;
      for (size_t i = 1; i < n; ++i) bytes += e.window[i].second;
      r.rate_hz = (n - 1) / span;
      r.bandwidth_Bps = bytes / span;
    }
    r.last_age_s = now_s - e.last_s;
    out[name] = r;
  }
  return out;
}

}  // namespace cairn::runtime
