#include "services/runtime/revolution_assembler.h"

#include <algorithm>
#include <iterator>

namespace cairn::runtime {

std::vector<common::LidarSlice> SplitSlice(const common::LidarSlice& whole, size_t max_bytes) {
  constexpr size_t kHeaderBytes = 512;
  const size_t per_slice =
      max_bytes > kHeaderBytes
          ? std::max<size_t>(1, (max_bytes - kHeaderBytes) / kBytesPerLidarPoint)
          : 1;
  const size_t n = whole.points.size();
  const size_t count = std::max<size_t>(1, (n + per_slice - 1) / per_slice);
  std::vector<common::LidarSlice> slices;
  slices.reserve(count);
  const double span = whole.azimuth_end_rad - whole.azimuth_start_rad;
  for (size_t i = 0; i < count; ++i) {
    common::LidarSlice s;
    s.utime = whole.utime;
    s.robot = whole.robot;
    s.revolution = whole.revolution;
    s.slice_index = static_cast<int32_t>(i);
    s.slice_count = static_cast<int32_t>(count);
    s.azimuth_start_rad = whole.azimuth_start_rad + span * i / count;
    s.azimuth_end_rad = whole.azimuth_start_rad + span * (i + 1) / count;
    s.max_range_m = whole.max_range_m;
    s.sensor_pose = whole.sensor_pose;
    const size_t begin = i * per_slice, end = std::min(n, begin + per_slice);
    s.points.assign(whole.points.begin() + begin, whole.points.begin() + end);
    slices.push_back(std::move(s));
  }
  return slices;
}

void RevolutionAssembler::Emit(std::map<Key, Pending>::iterator it,
                               std::vector<common::LidarRevolution>* done) {
  ++incomplete_;
  const common::LidarRevolution& rev = it->second.revolution;
  missing_slices_ += rev.expected_slices - static_cast<int64_t>(rev.slices.size());
  pending_points_ -= it->second.points;
  done->push_back(std::move(it->second.revolution));
  pending_.erase(it);
}

std::map<RevolutionAssembler::Key, RevolutionAssembler::Pending>::iterator
RevolutionAssembler::Oldest(const Key& keep) {
  auto oldest = pending_.end();
  for (auto it = pending_.begin(); it != pending_.end(); ++it) {
    if (it->first == keep) continue;
    if (oldest == pending_.end() || it->second.first_arrival_us < oldest->second.first_arrival_us) {
      oldest = it;
    }
  }
  return oldest;
}

std::vector<common::LidarRevolution> RevolutionAssembler::OnSlice(common::LidarSlice slice,
                                                                   int64_t arrival_us) {
  std::vector<common::LidarRevolution> done;
  const auto points = static_cast<int64_t>(slice.points.size());
  const Key key(slice.robot, slice.revolution);
  auto held = pending_.find(key);
  if (slice.slice_count <= 0 || slice.slice_count > limits_.max_slices_per_revolution ||
      slice.slice_index < 0 || slice.slice_index >= slice.slice_count ||
      points > limits_.max_points_per_slice || points > limits_.max_points_pending ||
      (held != pending_.end() && held->second.revolution.expected_slices != slice.slice_count)) {
    ++refused_slices_;
    return done;
  }
  // Revolutions that waited too long, and older ones of the same robot, are pushed out.
  for (auto it = pending_.begin(); it != pending_.end();) {
    const bool superseded = it->first.first == slice.robot && it->first.second < slice.revolution;
    const bool expired = arrival_us - it->second.first_arrival_us > limits_.timeout_us;
    if (it->first != key && (superseded || expired)) {
      if (expired && !superseded) ++expired_;
      auto next = std::next(it);
      Emit(it, &done);
      it = next;
    } else {
      ++it;
    }
  }
  // Room: a new revolution, or these points, push out the revolutions that came first.
  const bool is_new = pending_.count(key) == 0;
  while (!pending_.empty() &&
         ((is_new && static_cast<int>(pending_.size()) >= limits_.max_pending_revolutions) ||
          pending_points_ + points > limits_.max_points_pending)) {
    auto oldest = Oldest(key);
    if (oldest == pending_.end()) break;
    Emit(oldest, &done);
  }
  if (pending_points_ + points > limits_.max_points_pending) {
    ++refused_slices_;  // its own revolution fills the budget
    return done;
  }
  Pending& pending = pending_[key];
  common::LidarRevolution& rev = pending.revolution;
  if (is_new) {
    pending.first_arrival_us = arrival_us;
    rev.revolution = slice.revolution;
    rev.robot = slice.robot;
    rev.expected_slices = slice.slice_count;
  }
  const bool duplicate = std::any_of(rev.slices.begin(), rev.slices.end(), [&](const auto& s) {
    return s.slice_index == slice.slice_index;
  });
  if (!duplicate) {
    auto pos =
        std::lower_bound(rev.slices.begin(), rev.slices.end(), slice.slice_index,
                         [](const common::LidarSlice& s, int idx) { return s.slice_index < idx; });
    rev.slices.insert(pos, std::move(slice));
    pending.points += points;
    pending_points_ += points;
  }
  if (rev.complete()) {
    pending_points_ -= pending.points;
    done.push_back(std::move(rev));
    pending_.erase(key);
  }
  return done;
}

}  // namespace cairn::runtime
