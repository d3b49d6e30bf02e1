#include "services/explore/reactive_explorer.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace cairn::explore {
namespace {

// Seed 003 §7.3: N = 684, chunk = 136. Sectors: right [0, 136), front-right [136, 272),
// front [272, 408), front-left [408, 544), left [544, 684) (140 beams).
constexpr int kBeams = 684;
constexpr int kChunk = 136;
enum Sector { kRight = 0, kFrontRight = 1, kFront = 2, kFrontLeft = 3, kLeft = 4 };

int SectorBegin(Sector s) { return s * kChunk; }
int SectorEnd(Sector s) { return s == kLeft ? kBeams : (s + 1) * kChunk; }

std::vector<float> Uniform(float range_m = 10.f) { return std::vector<float>(kBeams, range_m); }

// Every beam of the sector set to `range_m`.
void FillSector(std::vector<float>* scan, Sector s, float range_m) {
  for (int i = SectorBegin(s); i < SectorEnd(s); ++i) (*scan)[i] = range_m;
}

// One beam in the middle of the sector set to `range_m` (the sector's minimum).
void PokeSector(std::vector<float>* scan, Sector s, float range_m) {
  (*scan)[(SectorBegin(s) + SectorEnd(s)) / 2] = range_m;
}

// A scan with the given sector minima (one beam each; the rest 10 m).
std::vector<float> Sectors(float right, float front_right, float front, float front_left,
                           float left) {
  std::vector<float> scan = Uniform();
  PokeSector(&scan, kRight, right);
  PokeSector(&scan, kFrontRight, front_right);
  PokeSector(&scan, kFront, front);
  PokeSector(&scan, kFrontLeft, front_left);
  PokeSector(&scan, kLeft, left);
  return scan;
}

void ExpectCommand(const VelocityCommand& c, double v_mps, double omega_radps) {
  EXPECT_DOUBLE_EQ(c.v_mps, v_mps);
  EXPECT_DOUBLE_EQ(c.omega_radps, omega_radps);
}

VelocityCommand OneStep(const std::vector<float>& scan, ReactiveParams params = {}) {
  ReactiveExplorer explorer(params);
  return explorer.Step(scan, 0.0);
}

TEST(ReactiveExplorerTest, OpenSpaceCruisesStraight) {  // test 20
  ReactiveExplorer explorer;
  ExpectCommand(explorer.Step(Uniform(), 0.0), 0.35, 0.0);
  EXPECT_EQ(explorer.state().mode, ReactiveMode::kCruise);
  EXPECT_FALSE(explorer.state().front_obstacle);
  EXPECT_EQ(explorer.state().scans, 1);
}

TEST(ReactiveExplorerTest, FrontObstacleTurnsTowardTheFreerSide) {  // test 21
  // Left + front-left = 8 + 8 beats right + front-right = 3 + 3: turn left.
  ExpectCommand(OneStep(Sectors(3.f, 3.f, 0.6f, 8.f, 8.f)), 0.0, +0.6);
  // Sides swapped: turn right.
  ExpectCommand(OneStep(Sectors(8.f, 8.f, 0.6f, 3.f, 3.f)), 0.0, -0.6);
  // Equal sums: ties go right.
  ExpectCommand(OneStep(Sectors(5.f, 3.f, 0.6f, 3.f, 5.f)), 0.0, -0.6);

  ReactiveExplorer explorer;
  explorer.Step(Sectors(3.f, 3.f, 0.6f, 8.f, 8.f), 0.0);
  EXPECT_EQ(explorer.state().mode, ReactiveMode::kTurnInPlace);
  EXPECT_EQ(explorer.state().turn_direction, +1);
  EXPECT_TRUE(explorer.state().front_obstacle);
}

TEST(ReactiveExplorerTest, FrontLateralThresholdIsTheSafetyDistanceOverOnePointFive) {  // 22
  EXPECT_NEAR(ReactiveParams{}.front_lateral_distance_m(), 0.4333, 1e-4);
  // Front-left 0.43 < 0.4333: obstacle, the robot stops.
  const VelocityCommand blocked_left = OneStep(Sectors(10.f, 10.f, 10.f, 0.43f, 10.f));
  EXPECT_EQ(blocked_left.v_mps, 0.0);
  EXPECT_NE(blocked_left.omega_radps, 0.0);
  // Front-left 0.44: clear, cruise.
  ExpectCommand(OneStep(Sectors(10.f, 10.f, 10.f, 0.44f, 10.f)), 0.35, 0.0);
  // The same on the front-right.
  EXPECT_EQ(OneStep(Sectors(10.f, 0.43f, 10.f, 10.f, 10.f)).v_mps, 0.0);
  ExpectCommand(OneStep(Sectors(10.f, 0.44f, 10.f, 10.f, 10.f)), 0.35, 0.0);
  // The front sector itself uses the full 0.65 m.
  EXPECT_EQ(OneStep(Sectors(10.f, 10.f, 0.64f, 10.f, 10.f)).v_mps, 0.0);
  ExpectCommand(OneStep(Sectors(10.f, 10.f, 0.66f, 10.f, 10.f)), 0.35, 0.0);
}

TEST(ReactiveExplorerTest, CriticalGlobalMinimumReversesStraight) {  // test 23
  for (const Sector s : {kRight, kFrontRight, kFront, kFrontLeft, kLeft}) {
    std::vector<float> scan = Sectors(10.f, 10.f, 0.6f, 10.f, 10.f);
    PokeSector(&scan, s, 0.20f);
    ReactiveExplorer explorer;
    ExpectCommand(explorer.Step(scan, 0.0), -0.15, 0.0);
    EXPECT_EQ(explorer.state().mode, ReactiveMode::kReverse) << "sector " << s;
    EXPECT_FLOAT_EQ(explorer.state().sectors.global_m, 0.20f);
  }
  // Just above the critical distance: a turn, not a reverse.
  ExpectCommand(OneStep(Sectors(0.26f, 10.f, 0.6f, 10.f, 10.f)), 0.0, +0.6);
}

TEST(ReactiveExplorerTest, TurnDirectionIsRememberedUntilTheFrontClears) {  // test 24
  ReactiveExplorer explorer;
  const std::vector<float> left_freer = Sectors(3.f, 3.f, 0.6f, 8.f, 8.f);
  const std::vector<float> right_freer = Sectors(8.f, 8.f, 0.6f, 3.f, 3.f);
  ExpectCommand(explorer.Step(left_freer, 0.0), 0.0, +0.6);
  // The right is now freer, but the memorised left turn is kept.
  ExpectCommand(explorer.Step(right_freer, 0.1), 0.0, +0.6);
  EXPECT_EQ(explorer.state().turn_direction, +1);
  // Front clear: memory reset.
  ExpectCommand(explorer.Step(Uniform(), 0.2), 0.35, 0.0);
  EXPECT_EQ(explorer.state().turn_direction, 0);
  // The next obstacle chooses afresh.
  ExpectCommand(explorer.Step(right_freer, 0.3), 0.0, -0.6);
  EXPECT_EQ(explorer.state().turn_direction, -1);
}

TEST(ReactiveExplorerTest, BlockedLongerThanTheLimitReversesUntilTheFrontClears) {  // test 25
  ReactiveExplorer explorer;
  const std::vector<float> blocked = Sectors(3.f, 3.f, 0.6f, 8.f, 8.f);  // min 0.6 >= 0.25
  for (const double t : {10.0, 10.5, 11.0, 11.5, 12.0}) {
    ExpectCommand(explorer.Step(blocked, t), 0.0, +0.6);
    EXPECT_EQ(explorer.state().mode, ReactiveMode::kTurnInPlace) << "t = " << t;
  }
  EXPECT_DOUBLE_EQ(explorer.state().blocked_s, 2.0);  // exactly the limit: still turning
  ASSERT_TRUE(explorer.state().block_start_s.has_value());
  EXPECT_DOUBLE_EQ(*explorer.state().block_start_s, 10.0);
  // First scan after 2.0 s: reverse straight, and keep reversing while the front is blocked.
  for (const double t : {12.05, 12.5, 13.0, 20.0}) {
    ExpectCommand(explorer.Step(blocked, t), -0.15, 0.0);
    EXPECT_EQ(explorer.state().mode, ReactiveMode::kReverse) << "t = " << t;
  }
  // Front clear: cruise, timer and memory reset.
  ExpectCommand(explorer.Step(Uniform(), 20.1), 0.35, 0.0);
  EXPECT_FALSE(explorer.state().block_start_s.has_value());
  EXPECT_EQ(explorer.state().blocked_s, 0.0);
  EXPECT_EQ(explorer.state().turn_direction, 0);
  // A new obstacle starts a new timer: turning again, not reversing.
  ExpectCommand(explorer.Step(blocked, 20.2), 0.0, +0.6);
  ExpectCommand(explorer.Step(blocked, 22.2), 0.0, +0.6);
  ExpectCommand(explorer.Step(blocked, 22.3), -0.15, 0.0);
}

TEST(ReactiveExplorerTest, AReverseThatDoesNotClearTheFrontEndsInATurnWhenCapped) {
  // Backed against a wall with the front still blocked: with max_reverse_s the reverse ends
  // after 3 s in a turn on a new block timer, then a new reverse; without it (the seed's rule,
  // the test above) it would reverse for ever.
  ReactiveParams p;
  p.max_reverse_s = 3.0;
  ReactiveExplorer explorer(p);
  const std::vector<float> blocked = Sectors(3.f, 3.f, 0.6f, 8.f, 8.f);
  for (const double t : {10.0, 11.0, 12.0}) ExpectCommand(explorer.Step(blocked, t), 0.0, +0.6);
  for (const double t : {12.1, 13.0, 15.1}) {
    ExpectCommand(explorer.Step(blocked, t), -0.15, 0.0);
    EXPECT_EQ(explorer.state().mode, ReactiveMode::kReverse) << "t = " << t;
  }
  // 3.1 s of reversing: the remembered side, on a timer started now.
  ExpectCommand(explorer.Step(blocked, 15.2), 0.0, +0.6);
  EXPECT_EQ(explorer.state().mode, ReactiveMode::kTurnInPlace);
  ASSERT_TRUE(explorer.state().block_start_s.has_value());
  EXPECT_DOUBLE_EQ(*explorer.state().block_start_s, 15.2);
  ExpectCommand(explorer.Step(blocked, 17.2), 0.0, +0.6);
  ExpectCommand(explorer.Step(blocked, 17.3), -0.15, 0.0);
  // A critical reading is capped the same way.
  ReactiveExplorer critical(p);
  const std::vector<float> close = Sectors(3.f, 3.f, 0.2f, 8.f, 8.f);
  ExpectCommand(critical.Step(close, 0.0), -0.15, 0.0);
  ExpectCommand(critical.Step(close, 3.0), -0.15, 0.0);
  EXPECT_EQ(critical.Step(close, 3.1).v_mps, 0.0);
  EXPECT_EQ(critical.state().mode, ReactiveMode::kTurnInPlace);
  p.max_reverse_s = -1.0;
  EXPECT_THROW(ReactiveExplorer bad(p), std::invalid_argument);
}

TEST(ReactiveExplorerTest, ACriticalReverseLeavesTheTurnSideUnchosen) {
  ReactiveExplorer explorer;
  ExpectCommand(explorer.Step(Sectors(3.f, 3.f, 0.2f, 8.f, 8.f), 0.0), -0.15, 0.0);
  EXPECT_EQ(explorer.state().turn_direction, 0);
  // Backed off to 0.6 m with the right now freer: the side is chosen now.
  ExpectCommand(explorer.Step(Sectors(8.f, 8.f, 0.6f, 3.f, 3.f), 0.1), 0.0, -0.6);
}

TEST(ReactiveExplorerTest, CloseSideWallsAreCentredWithTheLeftRuleFirst) {  // test 26
  ReactiveExplorer explorer;
  ExpectCommand(explorer.Step(Sectors(10.f, 10.f, 10.f, 10.f, 0.40f), 0.0), 0.28, -0.4);
  EXPECT_EQ(explorer.state().mode, ReactiveMode::kCentreRight);
  ExpectCommand(explorer.Step(Sectors(0.40f, 10.f, 10.f, 10.f, 10.f), 0.1), 0.28, +0.4);
  EXPECT_EQ(explorer.state().mode, ReactiveMode::kCentreLeft);
  ExpectCommand(explorer.Step(Sectors(0.40f, 10.f, 10.f, 10.f, 0.40f), 0.2), 0.28, -0.4);
  EXPECT_EQ(explorer.state().mode, ReactiveMode::kCentreRight);
  // 0.46 m on both sides is room enough.
  ExpectCommand(explorer.Step(Sectors(0.46f, 10.f, 10.f, 10.f, 0.46f), 0.3), 0.35, 0.0);
}

TEST(ReactiveExplorerTest, ACriticalSideWallWithAClearFrontCentresInsteadOfReversing) {  // 27
  ReactiveExplorer explorer;
  ExpectCommand(explorer.Step(Sectors(0.20f, 10.f, 10.f, 10.f, 10.f), 0.0), 0.28, +0.4);
  EXPECT_EQ(explorer.state().mode, ReactiveMode::kCentreLeft);
}

TEST(ReactiveExplorerTest, InvalidReadingsAreCleanedToTheReplacementRange) {  // test 28
  for (const float bad :
       {0.03f, 0.0f, -1.f, std::numeric_limits<float>::infinity(),
        -std::numeric_limits<float>::infinity(), 12.f, std::numeric_limits<float>::quiet_NaN()}) {
    std::vector<float> scan = Uniform(5.f);
    FillSector(&scan, kFront, bad);
    ReactiveExplorer explorer;
    ExpectCommand(explorer.Step(scan, 0.0), 0.35, 0.0);
    EXPECT_EQ(explorer.state().sectors.front_m, 10.0) << "reading " << bad;
    EXPECT_EQ(explorer.state().sectors.global_m, 5.0) << "reading " << bad;
  }
  // A valid short reading is kept (and is critical).
  std::vector<float> scan = Uniform(10.f);
  FillSector(&scan, kFront, 0.06f);
  ReactiveExplorer explorer;
  ExpectCommand(explorer.Step(scan, 0.0), -0.15, 0.0);
  EXPECT_FLOAT_EQ(explorer.state().sectors.front_m, 0.06f);
}

TEST(ReactiveExplorerTest, LegacyNanHidesAFrontObstacleAndTheRobotCruises) {  // test 28
  std::vector<float> scan = Sectors(3.f, 3.f, 0.6f, 8.f, 8.f);
  scan[SectorBegin(kFront)] = std::numeric_limits<float>::quiet_NaN();

  ReactiveExplorer fixed;
  ExpectCommand(fixed.Step(scan, 0.0), 0.0, +0.6);
  EXPECT_FLOAT_EQ(fixed.state().sectors.front_m, 0.6f);

  ReactiveParams legacy_params;
  legacy_params.legacy_nan = true;
  ReactiveExplorer legacy(legacy_params);
  // The source's bug: the front minimum is NaN, every comparison is false, the robot cruises
  // into the obstacle.
  ExpectCommand(legacy.Step(scan, 0.0), 0.35, 0.0);
  EXPECT_TRUE(std::isnan(legacy.state().sectors.front_m));
  EXPECT_TRUE(std::isnan(legacy.state().sectors.global_m));
  EXPECT_EQ(legacy.state().mode, ReactiveMode::kCruise);
}

TEST(ReactiveExplorerTest, LegacyNanElsewhereHidesTheCriticalDistance) {
  std::vector<float> scan = Sectors(3.f, 3.f, 0.2f, 8.f, 8.f);
  scan[SectorBegin(kRight)] = std::numeric_limits<float>::quiet_NaN();
  ReactiveParams legacy_params;
  legacy_params.legacy_nan = true;
  ReactiveExplorer legacy(legacy_params);
  // The global minimum is NaN, so 0.2 m ahead turns instead of reversing; the side sum with
  // the NaN compares false, so it turns right, toward the sector holding the NaN.
  ExpectCommand(legacy.Step(scan, 0.0), 0.0, -0.6);
  ExpectCommand(OneStep(scan), -0.15, 0.0);  // fixed mode reverses
}

TEST(ReactiveExplorerTest, SectorsSplitTheScanInFifthsWithTheRemainderOnTheLeft) {
  const struct {
    int beam;
    double SectorMinima::*field;
  } cases[] = {{0, &SectorMinima::right_m},         {135, &SectorMinima::right_m},
               {136, &SectorMinima::front_right_m}, {271, &SectorMinima::front_right_m},
               {272, &SectorMinima::front_m},       {407, &SectorMinima::front_m},
               {408, &SectorMinima::front_left_m},  {543, &SectorMinima::front_left_m},
               {544, &SectorMinima::left_m},        {683, &SectorMinima::left_m}};
  const double SectorMinima::*all[] = {&SectorMinima::right_m, &SectorMinima::front_right_m,
                                       &SectorMinima::front_m, &SectorMinima::front_left_m,
                                       &SectorMinima::left_m};
  for (const auto& c : cases) {
    std::vector<float> scan = Uniform();
    scan[c.beam] = 1.f;
    const SectorMinima s = ComputeSectorMinima(scan, ReactiveParams{});
    for (const double SectorMinima::*field : all) {
      EXPECT_EQ(s.*field, field == c.field ? 1.0 : 10.0) << "beam " << c.beam;
    }
    EXPECT_EQ(s.global_m, 1.0);
  }
}

TEST(ReactiveExplorerTest, FiveBeamsAreEnoughAndFewerThrow) {
  ReactiveExplorer explorer;
  EXPECT_THROW(explorer.Step({}, 0.0), std::invalid_argument);
  EXPECT_THROW(explorer.Step({10.f, 10.f, 10.f, 10.f}, 0.0), std::invalid_argument);
  EXPECT_EQ(explorer.state().scans, 0);
  ExpectCommand(explorer.Step({10.f, 10.f, 0.6f, 10.f, 10.f}, 0.0), 0.0, -0.6);
  // Seven beams: chunk 1, the left sector gets beams 4..6.
  const SectorMinima s = ComputeSectorMinima({9, 9, 9, 9, 9, 9, 1}, ReactiveParams{});
  EXPECT_EQ(s.left_m, 1.0);
  EXPECT_EQ(s.front_left_m, 9.0);
}

TEST(ReactiveExplorerTest, TimeMustBeFiniteAndNeverGoBackwards) {
  ReactiveExplorer explorer;
  EXPECT_THROW(explorer.Step(Uniform(), std::numeric_limits<double>::quiet_NaN()),
               std::invalid_argument);
  explorer.Step(Uniform(), 5.0);
  EXPECT_THROW(explorer.Step(Uniform(), 4.9), std::invalid_argument);
  EXPECT_NO_THROW(explorer.Step(Uniform(), 5.0));
  explorer.Reset();
  EXPECT_NO_THROW(explorer.Step(Uniform(), 0.0));
}

TEST(ReactiveExplorerTest, ResetForgetsTheTurnSideAndTheBlockTimer) {
  ReactiveExplorer explorer;
  explorer.Step(Sectors(3.f, 3.f, 0.6f, 8.f, 8.f), 0.0);
  EXPECT_EQ(explorer.state().turn_direction, +1);
  explorer.Reset();
  EXPECT_EQ(explorer.state().turn_direction, 0);
  EXPECT_FALSE(explorer.state().block_start_s.has_value());
  ExpectCommand(explorer.Step(Sectors(8.f, 8.f, 0.6f, 3.f, 3.f), 3.0), 0.0, -0.6);
  // The timer restarted at 3.0 s, so 4.0 s is not blocked too long.
  ExpectCommand(explorer.Step(Sectors(8.f, 8.f, 0.6f, 3.f, 3.f), 4.0), 0.0, -0.6);
}

TEST(ReactiveExplorerTest, BadParamsThrowNamingTheField) {
  const auto expect_throw_naming = [](ReactiveParams p, const std::string& field) {
    try {
      p.Validate();
      ADD_FAILURE() << field << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
    EXPECT_THROW(ReactiveExplorer{p}, std::invalid_argument);
    EXPECT_THROW(StatelessExplorer{p}, std::invalid_argument);
  };
  ReactiveParams p;
  EXPECT_NO_THROW(p.Validate());
  p.safety_distance_m = 0.0;
  expect_throw_naming(p, "safety_distance_m");
  p = {};
  p.front_lateral_divisor = -1.5;
  expect_throw_naming(p, "front_lateral_divisor");
  p = {};
  p.block_time_limit_s = std::numeric_limits<double>::quiet_NaN();
  expect_throw_naming(p, "block_time_limit_s");
  p = {};
  p.reverse_speed_mps = 0.15;
  expect_throw_naming(p, "reverse_speed_mps");
  p = {};
  p.clean_max_range_m = 0.01;
  expect_throw_naming(p, "clean_max_range_m");
  p = {};
  p.turn_rate_radps = std::numeric_limits<double>::infinity();
  expect_throw_naming(p, "turn_rate_radps");
}

TEST(ReactiveExplorerTest, ModesHaveTheirSeedNames) {
  EXPECT_STREQ(ReactiveModeName(ReactiveMode::kCruise), "CRUISE");
  EXPECT_STREQ(ReactiveModeName(ReactiveMode::kCentreLeft), "CENTRE_LEFT");
  EXPECT_STREQ(ReactiveModeName(ReactiveMode::kCentreRight), "CENTRE_RIGHT");
  EXPECT_STREQ(ReactiveModeName(ReactiveMode::kTurnInPlace), "TURN_IN_PLACE");
  EXPECT_STREQ(ReactiveModeName(ReactiveMode::kReverse), "REVERSE");
}

TEST(StatelessExplorerTest, PicksItsTurnSideAfreshOnEveryScan) {
  const std::vector<float> left_freer = Sectors(3.f, 3.f, 0.6f, 8.f, 8.f);
  const std::vector<float> right_freer = Sectors(8.f, 8.f, 0.6f, 3.f, 3.f);
  const StatelessExplorer baseline;
  ExpectCommand(baseline.Step(left_freer), 0.0, +0.6);
  // No memory: it flips to the right, where the stateful explorer keeps turning left.
  ExpectCommand(baseline.Step(right_freer), 0.0, -0.6);
  ExpectCommand(baseline.Step(left_freer), 0.0, +0.6);

  ReactiveExplorer stateful;
  stateful.Step(left_freer, 0.0);
  ExpectCommand(stateful.Step(right_freer, 0.1), 0.0, +0.6);
}

TEST(StatelessExplorerTest, NeverReversesEvenWhenCriticalOrStuck) {
  const std::vector<float> critical = Sectors(3.f, 3.f, 0.2f, 8.f, 8.f);
  const StatelessExplorer baseline;
  ReactiveExplorer stateful;
  for (int k = 0; k <= 50; ++k) {  // 5 s of scans at 10 Hz
    const StatelessDecision d = baseline.Decide(critical);
    EXPECT_EQ(d.mode, ReactiveMode::kTurnInPlace);
    ExpectCommand(d.command, 0.0, +0.6);
    EXPECT_EQ(stateful.Step(critical, 0.1 * k).v_mps, -0.15);
  }
  // Stuck at 0.6 m for long: the stateful explorer would reverse after 2 s.
  const std::vector<float> stuck = Sectors(3.f, 3.f, 0.6f, 8.f, 8.f);
  for (int k = 0; k < 50; ++k) EXPECT_GE(baseline.Step(stuck).v_mps, 0.0);
}

TEST(StatelessExplorerTest, ClearFrontBehavesLikeTheStatefulExplorer) {
  const StatelessExplorer baseline;
  ExpectCommand(baseline.Step(Uniform()), 0.35, 0.0);
  ExpectCommand(baseline.Step(Sectors(10.f, 10.f, 10.f, 10.f, 0.40f)), 0.28, -0.4);
  ExpectCommand(baseline.Step(Sectors(0.40f, 10.f, 10.f, 10.f, 10.f)), 0.28, +0.4);
  const StatelessDecision d = baseline.Decide(Sectors(0.40f, 10.f, 10.f, 10.f, 10.f));
  EXPECT_EQ(d.mode, ReactiveMode::kCentreLeft);
  EXPECT_FLOAT_EQ(d.sectors.right_m, 0.40f);
  EXPECT_THROW(baseline.Step({10.f, 10.f}), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::explore
