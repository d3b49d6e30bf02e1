// Seed 002's stop-and-scan next-best-view mission closed loop in the outdoor world: cairn-sim
// (the rover with its turret sweeping on request and its HDL-32E), cairn-mapper (the rover's
// cost layer from the lidar), cairn-navigator (drives to each view point) and cairn-explorer
// --mode nbv, as real processes on a private bus. The explorer asks the simulator for each scan
// over SIM.CONTROL, assembles the turret's lines, builds its information map and sends the next
// best view to the navigator. The mapper builds the same information map live as its explore
// layer (--explore-config), and cairn-mapstore saves it with the mapper's map.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cairn/lcmt_explore_status.hpp"
#include "cairn/lcmt_pose.hpp"

#include "common/channels.h"
#include "common/grid_map.h"
#include "mapstore/sqlite_map_store.h"
#include "tests/integration/mapstore/mapstore_fixture.h"
#include "tests/support/harness.h"

namespace cairn::explore {
namespace {

namespace ch = channels;
using testing::Bus;
using testing::ProcessSet;
using testing::WaitFor;

constexpr char kRobot[] = "rover";
constexpr int kScans = 4;
constexpr int kLinesPerScan = 360;  // 180 deg of pan in 0.5 deg steps

int Occurrences(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(NbvStackTest, StopsScansAndDrivesToTheNextBestViewUntilTheScanLimit) {
  ProcessSet procs(testing::PrivateLcmUrl());
  const std::string out = testing::TestTempDir() + "/report";
  const std::string db = testing::TestTempDir() + "/cairn.db";
  procs.Start("cairn-mapstore", {"--db", db});
  Bus bus(procs.url());
  const std::string status_channel = ch::ForRobot(kRobot, ch::kExploreStatus);
  bus.Keep(status_channel);
  auto& sim = procs.Start(
      "cairn-sim",
      {"--scenario", testing::SourcePath("config/sim/outdoor_nbv.yaml"), "--speed", "2"});
  procs.Start("cairn-mapper",
              {"--robot", kRobot, "--profiles", "rover", "--config",
               testing::SourcePath("config/mapping/mapper.yaml"), "--explore-config",
               testing::SourcePath("config/explore/outdoor_nbv.yaml")});
  procs.Start("cairn-navigator", {"--robot", kRobot, "--profile", "rover", "--config",
                                  testing::SourcePath("config/navigator/navigator.yaml")});
  auto& explorer =
      procs.Start("cairn-explorer", {"--robot", kRobot, "--profile", "rover", "--config",
                                     testing::SourcePath("config/explore/outdoor_nbv.yaml"),
                                     "--max-scans", std::to_string(kScans), "--duration", "600",
                                     "--out", out, "--save", "nbv_test/outdoor"});

  // Four scans of 7.2 simulated seconds and three drives of a few metres: about 40 s of wall
  // time at 2x; the bound allows for a slow machine.
  const bool done = WaitFor([&] { return !explorer.Running(); }, 400.0, [&] { bus.Pump(20); });
  for (int i = 0; i < 20; ++i) bus.Pump(10);
  ASSERT_TRUE(done) << "the explorer did not finish\n" << explorer.Log();
  const auto rc = explorer.WaitExit(5.0);
  ASSERT_TRUE(rc.has_value());
  EXPECT_EQ(*rc, 0) << explorer.Log();
  const std::string log = explorer.Log();

  // Its progress on the bus: scans and coverage never go back, and the last status says done
  // after the four scans, with the view points reached.
  std::vector<cairn::lcmt_explore_status> statuses;
  for (const auto& bytes : bus.Kept(status_channel)) {
    cairn::lcmt_explore_status s{};
    ASSERT_GE(s.decode(bytes.data(), 0, static_cast<int>(bytes.size())), 0);
    statuses.push_back(s);
  }
  ASSERT_FALSE(statuses.empty());
  int scans = 0;
  double coverage = 0.0;
  for (const auto& s : statuses) {
    EXPECT_EQ(s.mode, +cairn::lcmt_explore_status::MODE_NBV);
    EXPECT_GE(s.scans, scans);
    scans = s.scans;
    if (std::isfinite(s.coverage)) {
      EXPECT_GE(s.coverage, coverage - 1e-9);
      coverage = s.coverage;
    }
  }
  const auto& last = statuses.back();
  EXPECT_EQ(last.state, +cairn::lcmt_explore_status::STATE_DONE) << log;
  EXPECT_EQ(last.scans, kScans) << log;
  EXPECT_EQ(last.goals_sent, kScans - 1) << log;
  EXPECT_GE(last.goals_reached, kScans - 2) << log;
  // The first scan from the start area sees most of the 16 x 14 m work area (the turret
  // reaches 30 m); the next ones add to it.
  EXPECT_GE(last.coverage, 0.6) << log;
  EXPECT_GT(last.quality, 0.0) << log;
  EXPECT_GT(last.distance_m, 3.0) << log;
  EXPECT_NE(log.find("scan limit (4) is reached"), std::string::npos) << log;

  // The summary table (a row per scan) and the renders of the information map.
  std::ifstream summary_file(out + "/nbv_summary.txt");
  ASSERT_TRUE(summary_file.good()) << log;
  std::stringstream summary;
  summary << summary_file.rdbuf();
  EXPECT_NE(summary.str().find("4 scans"), std::string::npos) << summary.str();
  int rows = 0;
  for (std::string line; std::getline(summary, line);) {
    int scan = 0;
    double x = 0, y = 0;
    if (std::sscanf(line.c_str(), "%d %lf %lf", &scan, &x, &y) == 3) ++rows;
  }
  EXPECT_EQ(rows, kScans) << summary.str();
  for (const char* png : {"/nbv_navigability.png", "/nbv_quality.png"}) {
    EXPECT_GT(std::filesystem::file_size(out + png), 1000u) << png;
  }

  // The information map went to the map store: its layers come back from the SQLite file,
  // and the coverage they give is the one the explorer reported.
  EXPECT_NE(log.find("information map saved as nbv_test/outdoor version 1"), std::string::npos)
      << log;
  mapstore::SqliteOptions read_only;
  read_only.read_only = true;
  auto store = mapstore::SqliteMapStore::Open(db, read_only);
  ASSERT_TRUE(store.ok()) << store.status().ToString();
  mapstore::MapRef ref;
  ref.site = "nbv_test";
  ref.name = "outdoor";
  auto stored = (*store)->LoadLayers(ref, {});
  ASSERT_TRUE(stored.ok()) << stored.status().ToString();
  for (const char* layer : {"explore/navigability", "explore/quality", "explore/explored",
                            "explore/work_area", "explore/points"}) {
    EXPECT_TRUE(stored->HasLayer(layer)) << layer;
  }
  if (stored->HasLayer("explore/explored") && stored->HasLayer("explore/work_area")) {
    const common::Layer& explored = stored->at("explore/explored");
    const common::Layer& area = stored->at("explore/work_area");
    int64_t in_area = 0, seen = 0;
    for (int i = 0; i < area.size(); ++i) {
      if (area.data()[i] != 1.f) continue;
      ++in_area;
      seen += explored.data()[i] == 1.f;
    }
    ASSERT_GT(in_area, 0);
    EXPECT_NEAR(static_cast<double>(seen) / static_cast<double>(in_area), last.coverage, 1e-9);
  }

  // The mapper's explore layer, pulled from the live map into the store as the mapper's other
  // layers are, is the explorer's map: the same sweeps through the same code. Its own socket
  // may lose a turret line the explorer had (a no-return line in one sweep), so 1 % of the
  // cells may differ.
  {
    lcm::LCM lcm(procs.url());
    mapstore::MapstoreClient client(lcm, "nbv-stack-test",
                                    mapstore::testing::TestClientOptions(90));
    auto save =
        mapstore::testing::MakeRequest(mapstore::testing::Request::OP_SAVE, "nbv_test", "live");
    save.robot = kRobot;
    save.profile = "rover";
    auto saved = client.Call(save);
    ASSERT_TRUE(saved.ok()) << saved.status().ToString();
    ASSERT_EQ(saved->status, mapstore::testing::kStatusOk) << saved->message;
    std::string live_name;
    for (const auto& m : saved->maps) {
      if (m.name.rfind("live-explore", 0) == 0) live_name = m.name;
    }
    ASSERT_FALSE(live_name.empty()) << "no explore companion map in the pull save";
    mapstore::MapRef live_ref;
    live_ref.site = "nbv_test";
    live_ref.name = live_name;
    auto live = (*store)->LoadLayers(live_ref, {});
    ASSERT_TRUE(live.ok()) << live.status().ToString();
    ASSERT_TRUE(stored.ok());
    ASSERT_TRUE(live->geometry() == stored->geometry());
    const common::Layer& a = live->at("explore/navigability");
    const common::Layer& b = stored->at("explore/navigability");
    int64_t known = 0, same = 0;
    for (int i = 0; i < a.size(); ++i) {
      const float x = a.data()[i], y = b.data()[i];
      if (std::isnan(x) && std::isnan(y)) continue;
      ++known;
      same += !std::isnan(x) && !std::isnan(y) && std::abs(x - y) < 1e-4f;
    }
    ASSERT_GT(known, 100);
    EXPECT_GE(same, known * 99 / 100) << same << " of " << known << " known cells agree";
  }

  // Each scan was asked of the simulator, and the turret swept only when asked: at most one
  // sweep of lines per request, and a whole sweep per scan. The test's own socket may lose a
  // line or two of the 1440 under load (it did once in CI: 1439) while the explorer, whose
  // summary above counts every scan, had them all; 1 % is allowed for it.
  const std::string sim_log = sim.Log();
  const int triggers = Occurrences(sim_log, "triggered rover/turret");
  EXPECT_GE(triggers, kScans) << sim_log;
  const int64_t lines = bus.Count(ch::ForRobot(kRobot, ch::kTurretScan));
  EXPECT_GE(lines, int64_t{kScans} * kLinesPerScan * 99 / 100);
  EXPECT_LE(lines, int64_t{triggers} * kLinesPerScan);

  // The robot stood on its wheels all along (the ground truth's roll and pitch stay small).
  const auto pose = bus.Last<cairn::lcmt_pose>(ch::ForRobot(kRobot, ch::kPose));
  ASSERT_TRUE(pose.has_value());
  const double x = pose->orientation_wxyz[1], y = pose->orientation_wxyz[2];
  const double up_z = 1.0 - 2.0 * (x * x + y * y);  // world z of the body's z axis
  EXPECT_GT(up_z, std::cos(20.0 * M_PI / 180.0));
}

}  // namespace
}  // namespace cairn::explore
