// Seed 002 test 23 over real processes: the simple world (a house and a tree on a gentle hill,
// seed 002's work area), the four presets of table 6-2, each run with five candidate seeds,
// one run after the other. Each run is cairn-sim (the rover with only its turret, sweeping on
// request, at full speed), cairn-mapstore, and cairn-explorer --mode nbv --drive teleport
// --save: every view point is reached by SIM.CONTROL OP_RESET_ROBOT and the distance counted is
// the navigation tree's path, so the presets are compared on what they choose, not on how a
// navigator drives (the closed loop with cairn-navigator is nbv_stack_test's). The stored
// information map is then judged with `cairn-map eval` against the world's geometry: the
// coverage of the reachable cells of the work area (the thesis's coverage) and the precision
// of the cells the explorer calls safe. A run takes seconds of wall time.
//
// Which view comes next hangs on small differences (the robot settles a little differently
// after each teleport, the scan differs by a few points, the candidates move), so one run of a
// preset can differ a lot from the next (the balanced one took 21 to 33 scans in five runs).
// The thesis's relations are asserted on the median of five runs of each preset (three in the
// structured world, whose runs are longer).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
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
  int seed{0};
  int scans{0};
  double distance_m{0.0};
  double coverage{0.0};  ///< of the work area, as the explorer counts it, 0..1
  double quality{0.0};
  double reachable_coverage{NAN};  ///< cairn-map eval: reachable cells known, 0..1
  double free_precision{NAN};      ///< cairn-map eval: safe cells (C_nc > 0.7) truly free
  std::string log;
  std::string eval;
  std::string out_dir;  ///< the explorer's report
  bool done{false};
  int exit_code{-1};
};

// The number after "key": in one JSON object (NaN when absent or null).
double JsonNumber(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\":");
  if (at == std::string::npos) return NAN;
  const char* start = json.c_str() + at + key.size() + 3;
  char* end = nullptr;
  const double v = std::strtod(start, &end);
  return end == start ? NAN : v;
}

// One of seed 002's worlds: its explorer config, its shipped scenario and its name.
struct World {
  std::string name;      ///< simulator/worlds/<name>.xml
  std::string config;    ///< config/explore/<name>_nbv.yaml
  std::string scenario;  ///< the scenario without the lidar (TurretOnlyScenario)
};

// The shipped scenario of `world` without the lidar (no mapper or navigator here).
std::string TurretOnlyScenario(const std::string& world, const std::string& dir) {
  std::ifstream in(testing::SourcePath("config/sim/" + world + "_nbv.yaml"));
  const std::string path = dir + "/" + world + "_turret_only.yaml";
  std::ofstream out(path);
  for (std::string line; std::getline(in, line);) {
    if (line.find("hdl32e") == std::string::npos) out << line << "\n";
  }
  return path;
}

World SeedWorld(const std::string& name, const std::string& dir) {
  return {name, testing::SourcePath("config/explore/" + name + "_nbv.yaml"),
          TurretOnlyScenario(name, dir)};
}

PresetRun RunPreset(const std::string& preset, int seed, const World& world, const std::string& dir,
                    const std::string& max_scans = "80", const std::string& start = "0,0") {
  PresetRun run;
  run.preset = preset;
  run.seed = seed;
  const std::string run_dir = dir + "/" + preset + "-" + std::to_string(seed);
  ProcessSet procs(testing::PrivateLcmUrl(), run_dir);
  const std::string out = run_dir + "/report";
  const std::string db = run_dir + "/maps.db";
  procs.Start("cairn-mapstore", {"--db", db});
  procs.Start("cairn-sim", {"--scenario", world.scenario, "--speed", "0"});
  auto& explorer = procs.Start(
      "cairn-explorer", {"--robot",    kRobot,     "--profile",   "rover",   "--config",
                         world.config, "--preset", preset,        "--seed",  std::to_string(seed),
                         "--drive",    "teleport", "--max-scans", max_scans, "--duration",
                         "6000",       "--out",    out,           "--save",  "nbv/" + preset});
  // The figures come from the explorer's summary file: at full speed the simulator's messages
  // come by the ten thousand a second, more than a test's bus reads.
  run.done = WaitFor([&] { return !explorer.Running(); }, 400.0);
  if (const auto rc = explorer.WaitExit(5.0)) run.exit_code = *rc;
  run.log = explorer.Log();
  std::ifstream in(out + "/nbv_summary.txt");
  std::stringstream text;
  text << in.rdbuf();
  const std::string summary = text.str();
  double coverage_percent = 0.0;
  const size_t colon = summary.find("): ");
  if (colon != std::string::npos &&
      std::sscanf(summary.c_str() + colon + 3,
                  "%d scans, %lf m driven, coverage %lf %%, mean quality %lf", &run.scans,
                  &run.distance_m, &coverage_percent, &run.quality) == 4) {
    run.coverage = coverage_percent / 100.0;
  }
  run.out_dir = out;
  // The stored map against the world: the explorer's C_nc, within its work area, from the
  // start.
  auto& eval = procs.StartRaw("cairn-map eval",
                              {testing::BinPath("cairn-map"), "eval", "--db", db, "--site", "nbv",
                               "--map", preset, "--world", world.name, "--start", start, "--layer",
                               "explore/navigability", "--region", "explore/work_area", "--json"});
  if (eval.WaitExit(60.0)) {
    run.eval = eval.Log();
    run.reachable_coverage = JsonNumber(run.eval, "coverage");
    run.free_precision = JsonNumber(run.eval, "free_precision");
  }
  return run;
}

// One figure of every run of a preset.
template <typename T>
std::vector<double> Figures(const std::vector<PresetRun>& runs, const std::string& preset,
                            T PresetRun::*field) {
  std::vector<double> v;
  for (const PresetRun& r : runs) {
    if (r.preset == preset) v.push_back(static_cast<double>(r.*field));
  }
  return v;
}

// Mann-Whitney's U of "a above b": the pairs (a_i, b_j) with a_i > b_j, ties counting half. Of
// the 25 pairs of five runs against five, U <= 4 says b lies above a at the one-sided 5 % level
// (the table's critical value for n1 = n2 = 5).
double PairsAbove(const std::vector<double>& a, const std::vector<double>& b) {
  double u = 0.0;
  for (double x : a) {
    for (double y : b) u += x > y ? 1.0 : (x == y ? 0.5 : 0.0);
  }
  return u;
}
constexpr double kReversedAtFivePercent = 4.0;  // U of five runs against five

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Medians {
  double scans, distance_m, quality, coverage, reachable_coverage;
};

Medians MediansOf(const std::vector<PresetRun>& runs, const std::string& preset) {
  std::vector<double> scans, distance, quality, coverage, reachable;
  for (const PresetRun& r : runs) {
    if (r.preset != preset) continue;
    scans.push_back(r.scans);
    distance.push_back(r.distance_m);
    quality.push_back(r.quality);
    coverage.push_back(r.coverage);
    reachable.push_back(r.reachable_coverage);
  }
  return {Median(scans), Median(distance), Median(quality), Median(coverage), Median(reachable)};
}

// Runs every preset `seeds` times (expecting each to finish, exit 0, with a summary and an
// evaluation), prints every run and the medians beside the thesis's figures, and returns the
// medians in the presets' order.
std::vector<Medians> RunAll(const World& world, const std::vector<std::string>& presets,
                            const std::vector<std::string>& thesis, int seeds,
                            const std::string& dir, std::vector<PresetRun>* runs,
                            const std::string& max_scans = "80", const std::string& start = "0,0") {
  for (const std::string& preset : presets) {
    for (int seed = 1; seed <= seeds; ++seed) {
      runs->push_back(RunPreset(preset, seed, world, dir, max_scans, start));
      const PresetRun& r = runs->back();
      EXPECT_TRUE(r.done) << r.preset << " seed " << seed << " did not finish\n" << r.log;
      EXPECT_EQ(r.exit_code, 0) << r.preset << " seed " << seed << "\n" << r.log;
      EXPECT_GT(r.scans, 0) << r.preset << " seed " << seed << ": no summary\n" << r.log;
      EXPECT_TRUE(std::isfinite(r.reachable_coverage))
          << r.preset << " seed " << seed << ": no evaluation\n"
          << r.eval;
    }
  }
  std::printf("%s world\n", world.name.c_str());
  std::printf(
      "preset                    seed  scans  distance  quality  coverage  reachable  safe\n");
  for (const PresetRun& r : *runs) {
    std::printf("%-25s %3d  %5d  %6.1f m  %7.3f  %6.1f %%  %7.1f %%  %5.1f %%\n", r.preset.c_str(),
                r.seed, r.scans, r.distance_m, r.quality, 100.0 * r.coverage,
                100.0 * r.reachable_coverage, 100.0 * r.free_precision);
  }
  std::printf("\nmedians of %d runs        distance  quality  reachable  scans   | thesis\n",
              seeds);
  std::vector<Medians> m;
  for (size_t i = 0; i < presets.size(); ++i) {
    m.push_back(MediansOf(*runs, presets[i]));
    std::printf("%-25s %7.1f m  %7.3f  %7.1f %%  %5.0f   | %s\n", presets[i].c_str(),
                m[i].distance_m, m[i].quality, 100.0 * m[i].reachable_coverage, m[i].scans,
                thesis[i].c_str());
  }
  return m;
}

TEST(NbvPresetsTest, Seed002Test23TheSimpleWorldUnderTheFourPresetsOfTable62) {
  const std::string dir = testing::TestTempDir();
  std::vector<PresetRun> runs;
  const std::vector<Medians> m =
      RunAll(SeedWorld("simple", dir),
             {"simple-balanced", "simple-information", "simple-quality", "greedy"},
             {"106 m, 0.6846, 92.5 %, 12", "107 m, 0.6904, 94.1 %, 10", "128 m, 0.7503, 93.6 %, 13",
              "116 m, 0.5013, 91.4 %, 8"},
             5, dir, &runs);
  ASSERT_FALSE(HasFailure());
  const Medians& balanced = m[0];
  const Medians& information = m[1];
  const Medians& quality = m[2];
  const Medians& greedy = m[3];

  // The figure: the balanced preset covers 90 % of the reachable cells (the thesis's
  // coverage; the house's inside and roof are not reachable). 98.9..100 % in the runs made
  // while writing this test (config/explore/simple_nbv.yaml's d_max of 100 m; with 50 m the
  // utility presets stopped now and then at 89..93 %, the far side of the house not worth the
  // drive).
  EXPECT_GE(balanced.reachable_coverage, 0.90);
  // Table 6-3's relations. Medians of the test runs made while writing this test (d_max 100 m):
  // balanced 22..30 scans, 101..134 m, 0.62..0.67; information-dominant 19..24, 99..106 m,
  // 0.56..0.60; quality-dominant 31..38, 132..177 m, 0.69..0.70; greedy 8, 179..215 m,
  // 0.36..0.39. Asserted on the medians where the presets lie far apart in every test run:
  for (const Medians* other : {&information, &greedy}) {
    EXPECT_GT(quality.quality, other->quality) << "the quality-dominant preset";
  }
  EXPECT_GT(quality.distance_m, information.distance_m) << "the quality-dominant preset";
  for (const Medians* other : {&balanced, &information, &quality}) {
    EXPECT_LE(greedy.scans, other->scans) << "greedy";
    EXPECT_LT(greedy.quality, other->quality) << "greedy";
  }
  // Where they lie near (the quality-dominant preset's quality 0.03..0.08 above balanced's, its
  // distance 4..61 m longer; the information-dominant preset 0..9 scans fewer than balanced),
  // a median of five runs can fall either side, so these three assert that the runs do not say
  // the opposite at the one-sided 5 % level (Mann-Whitney's U of 4 or less; 15..25 of 25 pairs
  // in the expected order in the test runs made while writing this test).
  const double quality_pairs = PairsAbove(Figures(runs, "simple-quality", &PresetRun::quality),
                                          Figures(runs, "simple-balanced", &PresetRun::quality));
  const double distance_pairs =
      PairsAbove(Figures(runs, "simple-quality", &PresetRun::distance_m),
                 Figures(runs, "simple-balanced", &PresetRun::distance_m));
  const double scans_pairs = PairsAbove(Figures(runs, "simple-balanced", &PresetRun::scans),
                                        Figures(runs, "simple-information", &PresetRun::scans));
  std::printf(
      "pairs of runs in the thesis's order (of 25): quality-dominant above balanced in quality "
      "%.1f, in distance %.1f; information-dominant below balanced in scans %.1f\n",
      quality_pairs, distance_pairs, scans_pairs);
  EXPECT_GT(quality_pairs, kReversedAtFivePercent)
      << "the quality-dominant preset's quality against balanced's";
  EXPECT_GT(distance_pairs, kReversedAtFivePercent)
      << "the quality-dominant preset's distance against balanced's";
  EXPECT_GT(scans_pairs, kReversedAtFivePercent)
      << "the information-dominant preset's scans against balanced's";
  // Greedy's legs are the longest per scan, as in the thesis.
  EXPECT_GT(greedy.distance_m / greedy.scans, balanced.distance_m / balanced.scans);

  // `cairn-map eval` on every run: the cells the explorer would drive on (C_nc above 0.7) are
  // free in the world. A wrong one is a collision risk; 100 % in the runs made while writing
  // this test (99.2..100 % before the step term made the house's foot and the tree's trunk,
  // where a 0.3 m cell holds both ground and wall, unsafe).
  for (const PresetRun& r : runs) {
    EXPECT_GE(r.free_precision, 0.98) << r.preset << " seed " << r.seed << "\n" << r.eval;
  }
}

// Seed 002 test 24: the urban block (six buildings, streets with kerbs and gaps, parked cars, a
// 2.5 m passage) under the two presets of table 6-4.
TEST(NbvPresetsTest, Seed002Test24TheStructuredWorldUnderThePresetsOfTable64) {
  const std::string dir = testing::TestTempDir();
  std::vector<PresetRun> runs;
  const std::vector<Medians> m =
      RunAll(SeedWorld("structured", dir), {"structured-zones-quality", "structured-information"},
             {"352 m, 43 scans", "397 m, 39 scans"}, 3, dir, &runs);
  ASSERT_FALSE(HasFailure());
  const Medians& zones_quality = m[0];
  const Medians& information = m[1];
  // The figure: both presets cover 94 % of the reachable cells (98.5..100 % and
  // 96.2..98.5 % in the runs made while writing this test).
  EXPECT_GE(zones_quality.reachable_coverage, 0.94);
  EXPECT_GE(information.reachable_coverage, 0.94);
  // As in the thesis the information-dominant preset needs fewer scans (13..27 against 44..63
  // here; 39 against 43 there). Unlike the thesis it drives less too (130..175 m against
  // 224..321 m; 397 against 352 m there): not asserted.
  EXPECT_LT(information.scans, zones_quality.scans);
  // `cairn-map eval`: the safe cells are free in the world, kerbs included. Seed 002's F and B
  // read a 12 cm kerb as navigable ground; the information map's step term (the rover's 8 cm
  // step, nbv.max_step_m) makes its face and its edge unsafe: 97.7..99.3 % in the runs made
  // while writing this test, 93.1..93.9 % without the step term.
  for (const PresetRun& r : runs) {
    EXPECT_GE(r.free_precision, 0.96) << r.preset << " seed " << r.seed << "\n" << r.eval;
  }
}

// One row of the explorer's nbv_path.csv (services/explore/nbv_report.h).
struct PathRow {
  bool view{false};
  int index{0};
  double x_m{0.0}, y_m{0.0};
  int level{0};
  double ground_z_m{NAN}, cnc_when_chosen{NAN}, cnc_final{NAN};
};

std::vector<PathRow> ReadPathCsv(const std::string& path) {
  std::vector<PathRow> rows;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    PathRow r;
    char kind[8] = {0};
    char ground[32], chosen[32], final_cnc[32];
    if (std::sscanf(line.c_str(), "%7[^,],%d,%lf,%lf,%d,%31[^,],%31[^,],%31s", kind, &r.index,
                    &r.x_m, &r.y_m, &r.level, ground, chosen, final_cnc) != 8) {
      continue;
    }
    r.view = std::string(kind) == "view";
    r.ground_z_m = std::strtod(ground, nullptr);  // "nan" reads as NaN
    r.cnc_when_chosen = std::strtod(chosen, nullptr);
    r.cnc_final = std::strtod(final_cnc, nullptr);
    rows.push_back(r);
  }
  return rows;
}

// Seed 002 test 25: the unstructured world (simulator/worlds/unstructured.xml: a canyon 2.2 m
// deep, walled along its rims, entered by a ramp from the west; a bridge with parapets across
// it, the one pass between the world's halves; north of the bridge a basin that only a robot
// passing under the bridge sees) under the two presets of table 6-6, three runs each. The
// information map keeps two levels per cell (config/explore/unstructured_nbv.yaml's
// level_gap_m), so the deck and the canyon floor under it are both drivable.
TEST(NbvPresetsTest, Seed002Test25TheUnstructuredWorldOverAndUnderTheBridge) {
  const std::string dir = testing::TestTempDir();
  std::vector<PresetRun> runs;
  RunAll(SeedWorld("unstructured", dir), {"unstructured-balanced", "unstructured-information"},
         {"424 m, 0.7833, 88.35 %, 60", "290 m, 0.6013, 80.71 %, 46"}, 3, dir, &runs, "60",
         "15,15");
  ASSERT_FALSE(HasFailure());
  // The bridge's deck over the canyon's floor (x -4..0, y 6..9); the floor is the world's
  // lowest ground (z 0), the deck's top 2.2 m above it.
  auto on_deck_span = [](const PathRow& r) {
    return r.x_m > -4.0 && r.x_m < 0.0 && r.y_m > 6.0 && r.y_m < 9.0;
  };
  int runs_under = 0;
  for (const PresetRun& run : runs) {
    const std::string name = run.preset + " seed " + std::to_string(run.seed);
    const std::vector<PathRow> rows = ReadPathCsv(run.out_dir + "/nbv_path.csv");
    ASSERT_FALSE(rows.empty()) << name << ": no nbv_path.csv";
    int views = 0, path_cells = 0, blind = 0, safe_at_end = 0, over = 0, under = 0;
    double leg_start_x = 0.0, leg_start_y = 0.0;
    int leg = -1;
    for (const PathRow& r : rows) {
      if (r.view) {
        // Every visited pose is safe in the final map.
        ++views;
        EXPECT_GT(r.cnc_final, 0.7)
            << name << ": view " << r.index << " at (" << r.x_m << ", " << r.y_m << ")";
        continue;
      }
      ++path_cells;
      if (r.index != leg) {
        leg = r.index;
        leg_start_x = r.x_m;
        leg_start_y = r.y_m;
      }
      if (std::isnan(r.cnc_when_chosen)) {
        // Unexplored when chosen: only the scanner's blind cone under the robot (the tree's
        // robot_free_radius_m, 1.5 m) may be.
        ++blind;
        EXPECT_LE(std::hypot(r.x_m - leg_start_x, r.y_m - leg_start_y), 1.5 + 0.3)
            << name << ": leg " << r.index << " crosses an unexplored cell at (" << r.x_m << ", "
            << r.y_m << ")";
      } else {
        // Every path cell was safe when the leg was chosen.
        EXPECT_GT(r.cnc_when_chosen, 0.7)
            << name << ": leg " << r.index << " at (" << r.x_m << ", " << r.y_m << ")";
      }
      safe_at_end += r.cnc_final > 0.7;
      if (on_deck_span(r) && r.ground_z_m > 1.8) ++over;
      if (on_deck_span(r) && r.ground_z_m < 0.4) ++under;
    }
    std::printf(
        "%s: %d views, %d path cells (%d in the blind cone), %.1f %% safe in the final map; %d "
        "cells on the deck, %d under it\n",
        name.c_str(), views, path_cells, blind, 100.0 * safe_at_end / std::max(1, path_cells), over,
        under);
    // The final map, with every scan in it, still calls 97 % of the path safe: 98.7..99.4 % in
    // the runs made while writing this test (a cell or two of a leg is found a step later,
    // where the ground under the deck's ends or a crest was seen from below).
    EXPECT_GE(safe_at_end, 0.97 * path_cells) << name;
    // Over the bridge in every run: it is the one pass between the world's halves.
    EXPECT_GT(over, 0) << name << ": never on the deck";
    runs_under += under > 0;
    // `cairn-map eval` from the start: the safe cells are free in the world and the reachable
    // cells known (100 % and 96..97 % when the robot passed under the bridge, 86..89 % when it
    // spent its scans elsewhere, in the runs made while writing this test).
    EXPECT_GE(run.free_precision, 0.98) << name << "\n" << run.eval;
    EXPECT_GE(run.reachable_coverage, 0.80) << name << "\n" << run.eval;
  }
  // Under the bridge along the canyon's floor, into the basin: in 14 of 18 runs of the balanced
  // preset and 9 of 13 of the information-dominant one made while writing this test. The runs
  // that did not spent their 60 scans on quality elsewhere, the canyon's ramp far away. Two of
  // the six runs must (at 3 in 4 a run, all but one fail together once in 180 test runs).
  EXPECT_GE(runs_under, 2) << "runs that passed under the bridge";
  // Table 6-7: preset I drives further and scans more than preset II (424 against 290 m, 60
  // against 46 scans there; 270..470 m and 39..74 scans against 215..290 m and 35..51 here).
  // With three runs each only a full reversal (all nine pairs) is significant at 5 %.
  const double distance_pairs =
      PairsAbove(Figures(runs, "unstructured-balanced", &PresetRun::distance_m),
                 Figures(runs, "unstructured-information", &PresetRun::distance_m));
  const double scans_pairs =
      PairsAbove(Figures(runs, "unstructured-balanced", &PresetRun::scans),
                 Figures(runs, "unstructured-information", &PresetRun::scans));
  std::printf("pairs of runs (of 9) with preset I above II: distance %.1f, scans %.1f\n",
              distance_pairs, scans_pairs);
  EXPECT_GT(distance_pairs, 0.0);
  EXPECT_GT(scans_pairs, 0.0);
}

// Seed 002 test 26 over real processes: from the simple world's start, after the first scan,
// the information-heavy weights of table 6-8 (cartif-fast: 0.84, 0.10, 0.05, 0.05) hop far, to
// the border of what that scan saw; the quality-heavy ones with a high cost (cartif-quality:
// 0.35, 0.40, 0.15, 0.40) stay near the robot. Three runs of each, one leg each. (On a made map,
// NbvTest.Seed002Test26... checks the border itself.)
TEST(NbvPresetsTest, Seed002Test26InformationHeavyWeightsHopFarQualityHeavyOnesStayNear) {
  const std::string dir = testing::TestTempDir();
  const World world = SeedWorld("simple", dir);
  std::vector<double> fast_m, quality_m;
  for (const std::string preset : {"cartif-fast", "cartif-quality"}) {
    for (int seed = 1; seed <= 3; ++seed) {
      const PresetRun run = RunPreset(preset, seed, world, dir, "2");
      const std::string name = preset + " seed " + std::to_string(seed);
      ASSERT_TRUE(run.done) << name << "\n" << run.log;
      ASSERT_EQ(run.scans, 2) << name << "\n" << run.log;
      // The first leg: 4-neighbour steps of 0.3 m between its path cells.
      int cells = 0;
      for (const PathRow& r : ReadPathCsv(run.out_dir + "/nbv_path.csv")) {
        cells += !r.view && r.index == 1;
      }
      ASSERT_GT(cells, 1) << name;
      (preset == "cartif-fast" ? fast_m : quality_m).push_back(0.3 * (cells - 1));
    }
  }
  std::printf("first leg (m): cartif-fast");
  for (double d : fast_m) std::printf(" %.1f", d);
  std::printf("; cartif-quality");
  for (double d : quality_m) std::printf(" %.1f", d);
  std::printf("\n");
  // 9.9..13.2 m against 3.6..5.1 m in the runs made while writing this test: every fast hop is
  // longer than every quality one, and at least twice the candidates' 3 m spacing.
  for (double fast : fast_m) {
    EXPECT_GT(fast, 6.0);
    for (double quality : quality_m) EXPECT_GT(fast, quality);
  }
}

}  // namespace
}  // namespace cairn::explore
