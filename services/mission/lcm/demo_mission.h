#pragma once

#include <string>
#include <vector>

#include "cairn/lcmt_goal.hpp"

#include "common/grid_map.h"
#include "common/types.h"
#include "mapstore/lcm/mapstore_client.h"
#include "mapstore/map_io.h"
#include "services/mission/sonar_fan.h"
#include "services/mission/track_log.h"
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
  /// The stored base layer rendered with the path and the obstacles, and what the renders are
  /// cropped to: "elevation" for a terrain map, "sonar/occupancy" for the AUV's sonar map.
  std::string map_layer{"elevation"};
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
  std::vector<std::string> renders;    ///< PNG files, and the track CSV
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
  struct DriveState;
  bool Drive(MissionReport* report);
  cairn::lcmt_goal MakeGoal(int64_t goal_id) const;
  /// Sends the goal until the navigator answers and follows its status until the goal is
  /// reached, failed or cancelled (true) or the drive timed out or was interrupted (false).
  bool FollowGoal(cairn::lcmt_goal* goal, DriveState* state, MissionReport* report);
  bool StoreAndShare(MissionReport* report);
  bool PutProfiles(mapstore::MapstoreClient* client, const std::vector<std::string>& profiles,
                   MissionReport* report);
  bool SaveMap(mapstore::MapstoreClient* client, MissionReport* report);
  bool ShareMap(mapstore::MapstoreClient* client, MissionReport* report);
  bool RenderAndList(mapstore::MapstoreClient* client, const std::vector<std::string>& profiles,
                     MissionReport* report);
  bool Render(const std::string& name, const common::GridMap& map, const std::string& layer,
              const mapstore::io::PngOverlay& overlay, MissionReport* report);
  /// The planned-against-driven CSV, and when a sonar pinged, the fans of its first whole sweep
  /// (from the start) and of its last.
  bool WriteTrackAndSonar(MissionReport* report);

  runtime::Node* node_;
  MissionParams params_;
  std::vector<common::Vector2> driven_m_;
  TrackLog track_;
  SonarFan fan_;        ///< every ping: the last sweep
  SonarFan first_fan_;  ///< the pings of the head's first pass over its whole sector
  int64_t bad_messages_{0};  ///< paths, odometry and pings refused while driving
};

/// The summary printed at the end of the demo.
std::string FormatReport(const MissionParams& params, const MissionReport& report);

}  // namespace cairn::mission
