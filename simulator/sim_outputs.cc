#include "simulator/sim_outputs.h"

namespace cairn::sim {

void SimOutputs::Clear() {
  for (auto& group : groups_) group->Clear();
  events.clear();
}

bool SimOutputs::empty() const {
  for (const auto& group : groups_) {
    if (!group->empty()) return false;
  }
  return events.empty();
}

ReadingGroup* SimOutputs::Find(const std::string& sensor) const {
  for (const auto& group : groups_) {
    if (group->sensor() == sensor) return group.get();
  }
  return nullptr;
}

}  // namespace cairn::sim
