#pragma once

#include <string>
#include <vector>

#include "common/types.h"
#include "services/runtime/node.h"

/// @file
/// The demo mission: drive a robot to a goal through the running graph, store the map it made,
/// share it with other robot profiles, and report. It is a client of the running processes
/// (cairn-navigator, cairn-mapper, cairn-mapstore): everything goes over LCM.

namespace cairn::mission {

struct MissionParams {
  std::string robot{"p3at"};
  std::string source_profile{"pioneer3at"};
  std::vector<std::string> share_profiles{"rover"};
  std::string profiles_dir{"config/profiles"};
  common::Pose2 goal{21.0, 38.0, 0.0};
  bool goal_has_yaw{false};
  std::string site{"tunnel"};
  std::string map_name{"demo"};
  std::string out_dir{"var/demo"};
  double timeout_s{600.0};          ///< wall-clock bound on the drive
  double ready_timeout_s{120.0};    ///< wall-clock bound on waiting for the graph
};

/// What the mission measured (printed as the summary).
struct MissionReport {
  bool reached{false};
  std::string nav_outcome;       ///< "reached", or the failure reason
  double distance_m{0.0};
  double sim_time_s{0.0};
  double wall_time_s{0.0};
  double real_time_factor{0.0};
  int replans{0};
  int recoveries{0};
  int64_t map_version{0};
  std::vector<std::string> renders;
  std::vector<std::string> obstacle_lines;  ///< one line per obstacle with each profile's verdict
  std::string error;             ///< the first thing that went wrong (empty on success)
  bool ok() const { return reached && error.empty(); }
};

class DemoMission {
 public:
  DemoMission(runtime::Node* node, MissionParams params);
  /// Runs the whole mission; never throws.
  MissionReport Run();

 private:
  bool WaitForGraph(MissionReport* report);
  bool Drive(MissionReport* report);
  bool StoreAndShare(MissionReport* report);

  runtime::Node* node_;
  MissionParams params_;
  std::vector<common::Vector2> driven_m_;
};

/// The summary printed at the end of the demo.
std::string FormatReport(const MissionParams& params, const MissionReport& report);

}  // namespace cairn::mission
