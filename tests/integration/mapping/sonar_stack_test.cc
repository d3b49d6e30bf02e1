// Seed 004's sonar over real processes: cairn-sim's imaging sonar and cairn-mapper's sonar layer
// on a private bus.
// - A Pioneer 3-DX carrying the sonar on its laser mount (0.3 m over the floor: the seed's
//   ground-robot variant) in the closed 16 x 14 m hall, 1 m from the south wall facing north; the
//   head sweeps from 35 deg (towards the west wall, 8 m away).
// - The Sparus II AUV hovering 2.2 m over the seabed at (0, 0), facing east, in the underwater
//   worlds: floor (test 17), breakwater (test 14, stationary for a full sweep), cave (test 15).

#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_occupancy_tile.hpp"
#include "cairn/lcmt_sonar_detection.hpp"
#include "cairn/lcmt_sonar_ping.hpp"

#include "common/channels.h"
#include "common/grid_map.h"
#include "services/runtime/layer_assembler.h"
#include "tests/support/harness.h"
#include "tests/support/sonar_layer.h"

namespace cairn::mapping {
namespace {

namespace ch = channels;
using testing::Bus;
using testing::Cluster;
using testing::Clusters;
using testing::CountCells;
using testing::ProcessSet;
using testing::SonarTiles;
using testing::WaitFor;

constexpr char kRobot[] = "p3dx";
constexpr char kAuv[] = "auv";
constexpr char kLayer[] = "sonar/occupancy";

struct Cells {
  // Occupied up to a bin and a cell in front of the west wall's face (x = 0): a peak lies at
  // its 1 m bin's near edge, as the thesis placed it.
  int wall{0};
  int interior{0};  // occupied anywhere else inside the hall
  int free{0};
};

Cells Count(const common::GridMap& map) {
  Cells c;
  const common::Layer& l = map.at(kLayer);
  for (int iy = 0; iy < map.size_y(); ++iy) {
    for (int ix = 0; ix < map.size_x(); ++ix) {
      const float v = l(ix, iy);
      if (std::isnan(v)) continue;
      const common::Vector2 at = map.CenterOf({ix, iy});
      if (v < 50.f) {
        ++c.free;
        continue;
      }
      if (at.x() < 1.25 && at.y() > 0.0 && at.y() < 14.0) {
        ++c.wall;
      } else if (at.x() > 1.25 && at.x() < 15.5 && at.y() > 0.5 && at.y() < 13.5) {
        ++c.interior;
      }
    }
  }
  return c;
}

// The west wall's echoes become occupied cells at the wall; the floor's never do (seed 004
// test 17's property: a grazing floor echoes under the 110 threshold); the water the beams
// crossed is free.
TEST(SonarStackTest, TheWallsEchoesAreObstaclesAndTheFloorsAreNot) {
  ProcessSet procs(testing::PrivateLcmUrl());
  const std::string scenario = procs.dir() + "/hall_sonar.yaml";
  std::ofstream(scenario) << "world: hall\n"
                             "seed: 1\n"
                             "robots:\n"
                             "  - id: p3dx\n"
                             "    model: p3dx\n"
                             "    spawn: {x_m: 8.0, y_m: 1.0, yaw_deg: 90.0}\n"
                             "    sensors:\n"
                             "      sonar: {mount_site: laser_mount}\n"
                             "      ground_truth: {}\n";
  const std::string config = procs.dir() + "/mapper.yaml";
  std::ofstream(config) << "pose_source: ground_truth\n"
                           "profiles: [p3dx]\n"
                           "occupancy_period_s: 0.5\n"
                           "octomap: {enabled: false}\n"
                           "sonar: {enabled: true, publish_period_s: 0.5}\n";
  Bus bus(procs.url());
  SonarTiles tiles(bus.lcm(), kRobot);
  procs.Start("cairn-sim", {"--scenario", scenario, "--speed", "2"});
  auto& mapper = procs.Start("cairn-mapper", {"--robot", kRobot, "--config", config});
  // 88 pings take the head from 35 deg to 60 deg: the west wall, 8 to 14 m off, all along.
  const std::string pings = ch::ForRobot(kRobot, ch::kSonar);
  Cells cells;
  const bool mapped = WaitFor(
      [&] {
        const auto map = tiles.Layer();
        if (!map) return false;
        cells = Count(*map);
        return bus.Count(pings) >= 80 && cells.wall >= 10;
      },
      60.0, [&] { bus.Pump(20); });
  ASSERT_TRUE(mapped) << bus.Count(pings) << " pings heard, " << cells.wall
                      << " wall cells occupied\n"
                      << mapper.Log();
  EXPECT_EQ(cells.interior, 0) << "an obstacle where the hall is open floor";
  EXPECT_GT(cells.free, 200) << "the beams cleared no water";
  const auto ping = bus.Last<cairn::lcmt_sonar_ping>(pings);
  ASSERT_TRUE(ping.has_value());
  EXPECT_EQ(ping->num_bins, 50);
  EXPECT_EQ(ping->frame, "sonar");
  EXPECT_NE(mapper.Log().find("sonar: first ping mapped"), std::string::npos) << mapper.Log();
}

// --- the AUV in the underwater worlds ---------------------------------------------------------

// cairn-sim with the AUV in `world` (hovering at the start: no commands) and cairn-mapper with
// the sonar layer only, at --speed `speed`.
struct AuvRig {
  ProcessSet procs{testing::PrivateLcmUrl()};
  Bus bus{procs.url()};
  SonarTiles tiles{bus.lcm(), kAuv};
  testing::ChildProcess* mapper{nullptr};

  AuvRig(const std::string& world, const std::string& speed) {
    const std::string scenario = procs.dir() + "/" + world + "_auv.yaml";
    std::ofstream(scenario) << "world: " << world << "\n"
                            << "seed: 1\n"
                               "robots:\n"
                               "  - id: auv\n"
                               "    model: sparus2\n"
                               "    spawn: {x_m: 0.0, y_m: 0.0, yaw_deg: 0.0}\n";
    const std::string config = procs.dir() + "/mapper.yaml";
    std::ofstream(config) << "pose_source: ground_truth\n"
                             "profiles: [sparus2_msis]\n"
                             "octomap: {enabled: false}\n"
                             "sonar: {enabled: true, publish_period_s: 0.5}\n";
    bus.Keep(ch::ForRobot(kAuv, ch::kSonar));
    procs.Start("cairn-sim", {"--scenario", scenario, "--speed", speed});
    mapper = &procs.Start("cairn-mapper", {"--robot", kAuv, "--config", config});
  }

  // Waits for `pings` pings and a layer published after the last of them.
  std::optional<common::GridMap> LayerAfter(int64_t pings, double timeout_s) {
    const std::string channel = ch::ForRobot(kAuv, ch::kSonar);
    int64_t version_then = -2;
    std::optional<common::GridMap> map;
    const bool done = WaitFor(
        [&] {
          if (version_then == -2) {
            if (bus.Count(channel) < pings) return false;
            version_then = tiles.version();
            return false;
          }
          if (tiles.version() <= version_then) return false;
          map = tiles.Layer();
          return map.has_value();
        },
        timeout_s, [&] { bus.Pump(20); });
    if (!done) return std::nullopt;
    return map;
  }
};

// A full sweep is 840 pings (two passes of 420 over the 120 deg sector); the first reaches the
// far limit after 88.
constexpr int64_t kFullSweepPings = 88 + 840;

// Test 17: over a full sweep of a flat seabed no occupied cell is added (its grazing echoes stay
// under the peak threshold of 110) and the beams, finding nothing, clear the water to range.
TEST(SonarStackTest, Seed004Test17FloorOnlyAddsNoObstacle) {
  AuvRig rig("floor", "10");
  const auto map = rig.LayerAfter(kFullSweepPings, 120.0);
  ASSERT_TRUE(map.has_value()) << rig.bus.Count(ch::ForRobot(kAuv, ch::kSonar)) << " pings heard\n"
                               << rig.mapper->Log();
  EXPECT_EQ(CountCells(*map, true), 0) << "seabed echoes became obstacles";
  // The +-60 deg sector to 50 m is about 2600 m^2: 42,000 cells of 0.25 m.
  EXPECT_GT(CountCells(*map, false), 30000);
}

// Test 14, stationary: after a full sweep the four columns are four distinct clusters, one at
// each column, and the front arc each column turns to the sonar is mapped across its width.
TEST(SonarStackTest, Seed004Test14BreakwaterColumnsAreFourClustersWithTheirFrontArcs) {
  AuvRig rig("breakwater", "10");
  const auto map = rig.LayerAfter(kFullSweepPings, 120.0);
  ASSERT_TRUE(map.has_value()) << rig.mapper->Log();
  const std::vector<common::Vector2> columns = {
      {18.0, -13.5}, {18.0, -4.5}, {18.0, 4.5}, {18.0, 13.5}};
  const double radius_m = 1.5;
  const std::vector<Cluster> clusters = Clusters(*map);
  std::string listed;
  for (const Cluster& c : clusters) {
    listed += " (" + std::to_string(c.centre.x()) + ", " + std::to_string(c.centre.y()) +
              "): " + std::to_string(c.cells);
  }
  ASSERT_EQ(clusters.size(), 4u) << "clusters:" << listed;
  for (const common::Vector2& column : columns) {
    int at_column = 0;
    for (const Cluster& c : clusters) {
      if ((c.centre - column).norm() < radius_m + 1.5) ++at_column;
    }
    EXPECT_EQ(at_column, 1) << "column at (" << column.x() << ", " << column.y() << ")";
    // The front arc: the bearings from the head (0.7, 0) the column covers, in 1 deg steps,
    // each holds an occupied cell within 1.5 m of the column's face.
    const common::Vector2 head(0.7, 0.0);
    const common::Vector2 to = column - head;
    const double bearing = std::atan2(to.y(), to.x());
    const double half = std::asin(radius_m / to.norm());
    const int steps = static_cast<int>(std::floor(2.0 * half / (M_PI / 180.0)));
    std::vector<char> covered(steps, 0);
    const common::Layer& l = map->at(kLayer);
    for (int iy = 0; iy < map->size_y(); ++iy) {
      for (int ix = 0; ix < map->size_x(); ++ix) {
        const float v = l(ix, iy);
        if (std::isnan(v) || v < 50.f) continue;
        const common::Vector2 at = map->CenterOf({ix, iy});
        if ((at - column).norm() > radius_m + 1.5) continue;
        const double b = std::atan2((at - head).y(), (at - head).x()) - (bearing - half);
        const int k = static_cast<int>(std::floor(b / (M_PI / 180.0)));
        if (k >= 0 && k < steps) covered[k] = 1;
      }
    }
    EXPECT_EQ(std::count(covered.begin(), covered.end(), 1), steps)
        << "front arc of the column at y = " << column.y() << " not mapped across";
  }
}

// Test 13's map from the start: after a full sweep the two rocks in the head's sight (rock_1 at
// (9, 1) and rock_2 at (15, -2.6); rock_1 hides rock_3 and rock_4 behind it) are one cluster
// each, at their faces, and nothing else is occupied.
TEST(SonarStackTest, Seed004Test13TheRocksInSightAreClustersAtTheirFaces) {
  AuvRig rig("rocks", "10");
  const auto map = rig.LayerAfter(kFullSweepPings, 120.0);
  ASSERT_TRUE(map.has_value()) << rig.mapper->Log();
  const std::vector<Cluster> clusters = Clusters(*map);
  std::string listed;
  for (const Cluster& c : clusters) {
    listed += " (" + std::to_string(c.centre.x()) + ", " + std::to_string(c.centre.y()) +
              "): " + std::to_string(c.cells);
  }
  ASSERT_EQ(clusters.size(), 2u) << "clusters:" << listed;
  // Each within its rock's size plus a bin of the rock's centre: rock_1 r 1.5 m, rock_2 a 3 x
  // 3.6 m box (half diagonal 2.3 m).
  const std::vector<std::pair<common::Vector2, double>> rocks = {{{9.0, 1.0}, 1.5 + 1.0},
                                                                 {{15.0, -2.6}, 2.3 + 1.0}};
  for (const auto& [centre, reach_m] : rocks) {
    int near = 0;
    for (const Cluster& c : clusters) near += (c.centre - centre).norm() < reach_m;
    EXPECT_EQ(near, 1) << "rock at (" << centre.x() << ", " << centre.y()
                       << "); clusters:" << listed;
  }
}

// Test 15: in the U-shaped cave the first ping's profile peaks at the nearest wall (the north
// wall, 12.2 m along the head's 35 deg) and nothing echoes behind it: a shadow to the end.
TEST(SonarStackTest, Seed004Test15CaveProfilePeaksAtTheNearestWallThenShadowToTheEnd) {
  AuvRig rig("cave", "2");
  const std::string channel = ch::ForRobot(kAuv, ch::kSonar);
  ASSERT_TRUE(
      WaitFor([&] { return rig.bus.Count(channel) >= 1; }, 30.0, [&] { rig.bus.Pump(20); }));
  cairn::lcmt_sonar_ping first;
  const auto& kept = rig.bus.Kept(channel);
  ASSERT_GE(first.decode(kept[0].data(), 0, static_cast<int>(kept[0].size())), 0);
  ASSERT_EQ(first.num_bins, 50);
  const auto& bins = first.intensities;
  const int peak = static_cast<int>(std::max_element(bins.begin(), bins.end()) - bins.begin());
  const double wall_m = 7.0 / std::sin(35.0 * M_PI / 180.0);  // 12.2 m
  EXPECT_GE(peak, static_cast<int>(wall_m) - 1);
  EXPECT_LE(peak, static_cast<int>(wall_m / std::cos(20.0 * M_PI / 180.0)));
  EXPECT_GE(bins[peak], 110) << "the wall's echo is under the peak threshold";
  // The seabed echoes before it, weaker; behind the wall's last echo, only shadow.
  int echoes_before = 0;
  for (int b = 0; b < peak; ++b) echoes_before += bins[b] > 0 && bins[b] < 110;
  EXPECT_GT(echoes_before, 3);
  for (int b = peak + 2; b < 50; ++b) EXPECT_EQ(bins[b], 0) << "bin " << b << " behind the wall";
  // The mapper puts the wall on its layer, and says per ping what it found: the first ping's
  // obstacle on the north wall's face (at the peak bin's near edge, up to a bin in front of it).
  rig.bus.Keep(ch::ForRobot(kAuv, ch::kSonarDetections));
  const auto map = rig.LayerAfter(20, 60.0);
  ASSERT_TRUE(map.has_value()) << rig.mapper->Log();
  int wall_cells = 0;
  for (const Cluster& c : Clusters(*map)) {
    if (c.centre.y() > 5.5 && c.centre.x() > 6.0) wall_cells += c.cells;
  }
  EXPECT_GT(wall_cells, 0) << "the north wall is not on the sonar layer";
  const auto detection =
      rig.bus.Last<cairn::lcmt_sonar_detection>(ch::ForRobot(kAuv, ch::kSonarDetections));
  ASSERT_TRUE(detection.has_value()) << "no per-ping detections on the bus";
  EXPECT_GE(rig.bus.Count(ch::ForRobot(kAuv, ch::kSonarDetections)), 10);
  EXPECT_EQ(detection->robot, kAuv);
  EXPECT_GE(detection->num_obstacles, 1) << "a ping at the cave's wall found nothing";
  for (int i = 0; i < detection->num_obstacles; ++i) {
    EXPECT_GT(detection->y_m[i], 7.0 - 1.5) << "obstacle " << i << " off the north wall";
    EXPECT_LE(detection->y_m[i], 7.0 + 0.01);
  }
}

}  // namespace
}  // namespace cairn::mapping
