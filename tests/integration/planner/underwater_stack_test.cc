// Seed 004's avoidance over real processes: cairn-sim with the Sparus II AUV in the rocks world
// (config/sim/rocks_sparus2.yaml), cairn-mapper with the sonar layer alone
// (config/mapping/underwater.yaml) and cairn-navigator planning on it with unknown water as an
// obstacle and commanding through the velocity bridge (config/navigator/underwater.yaml), on a
// private bus.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cairn/lcmt_body_velocity_request.hpp"
#include "cairn/lcmt_goal.hpp"
#include "cairn/lcmt_nav_status.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_velocity_command.hpp"

#include "common/channels.h"
#include "tests/support/harness.h"
#include "tests/support/sonar_layer.h"

namespace cairn::planner {
namespace {

namespace ch = channels;
using common::Vector2;
using testing::Bus;
using testing::Cluster;
using testing::Clusters;
using testing::ProcessSet;
using testing::SonarTiles;
using testing::WaitFor;

constexpr char kRobot[] = "auv";
constexpr int kStateReached = cairn::lcmt_nav_status::STATE_REACHED;
constexpr int kStateFailed = cairn::lcmt_nav_status::STATE_FAILED;

// A rock of the rocks world (simulator/worlds/generate_worlds.py, ROCKS): its outline.
struct Rock {
  std::string name;
  Vector2 centre;
  std::vector<Vector2> outline;  // a convex polygon (a cylinder as a 48-gon)
};

std::vector<Rock> RocksWorld() {
  auto cylinder = [](const std::string& name, Vector2 c, double r) {
    Rock rock{name, c, {}};
    for (int i = 0; i < 48; ++i) {
      const double a = 2.0 * M_PI * i / 48;
      rock.outline.push_back(c + r * Vector2(std::cos(a), std::sin(a)));
    }
    return rock;
  };
  auto box = [](const std::string& name, Vector2 c, double hx, double hy, double yaw_deg) {
    Rock rock{name, c, {}};
    const double a = yaw_deg * M_PI / 180.0;
    const Eigen::Rotation2Dd r(a);
    for (const Vector2& v :
         {Vector2(hx, hy), Vector2(-hx, hy), Vector2(-hx, -hy), Vector2(hx, -hy)}) {
      rock.outline.push_back(c + r * v);
    }
    return rock;
  };
  return {cylinder("rock_1", {9.0, 1.0}, 1.5), box("rock_2", {15.0, -2.6}, 1.5, 1.8, 30.0),
          cylinder("rock_3", {21.0, 2.6}, 2.0), box("rock_4", {27.0, -1.2}, 1.2, 1.6, -20.0)};
}

// Distance from a point to a convex polygon's boundary (0 inside).
double DistanceTo(const std::vector<Vector2>& poly, const Vector2& p) {
  bool inside = true;
  double best = 1e300;
  for (size_t i = 0; i < poly.size(); ++i) {
    const Vector2 a = poly[i], b = poly[(i + 1) % poly.size()];
    const Vector2 e = b - a;
    const double t = std::clamp((p - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * e - p).norm());
    if (e.x() * (p - a).y() - e.y() * (p - a).x() < 0.0) inside = false;
  }
  return inside ? 0.0 : best;
}

// The hull's clearance from a rock: the capsule's axis (1.37 m) sampled every 5 cm, less its
// 0.115 m radius.
double HullClearance(const Rock& rock, const common::Pose2& pose) {
  double best = 1e300;
  const Vector2 axis(std::cos(pose.yaw_rad), std::sin(pose.yaw_rad));
  for (double s = -0.685; s <= 0.685 + 1e-9; s += 0.05) {
    best = std::min(best, DistanceTo(rock.outline, pose.position() + s * axis));
  }
  return best - 0.115;
}

class UnderwaterStackTest : public ::testing::Test {
 protected:
  UnderwaterStackTest()
      : procs_(testing::PrivateLcmUrl()), bus_(procs_.url()), tiles_(bus_.lcm(), kRobot) {
    bus_.Keep(ch::ForRobot(kRobot, ch::kPose));
    bus_.Keep(ch::ForRobot(kRobot, ch::kBodyVelocity));
  }

  void Start(const std::string& speed) {
    procs_.Start("cairn-sim", {"--scenario", testing::SourcePath("config/sim/rocks_sparus2.yaml"),
                               "--speed", speed});
    mapper_ = &procs_.Start(
        "cairn-mapper",
        {"--robot", kRobot, "--config", testing::SourcePath("config/mapping/underwater.yaml")});
    navigator_ =
        &procs_.Start("cairn-navigator", {"--robot", kRobot, "--profile", "sparus2", "--config",
                                          testing::SourcePath("config/navigator/underwater.yaml")});
  }

  void SendGoal(int64_t id, double x, double y) {
    cairn::lcmt_goal g{};
    g.robot = kRobot;
    g.goal_id = id;
    g.kind = cairn::lcmt_goal::KIND_POSE;
    g.x_m = x;
    g.y_m = y;
    auto last_sent = std::chrono::steady_clock::now() - std::chrono::seconds(2);
    ASSERT_TRUE(WaitFor(
        [&] {
          auto s = Status();
          if (s && s->goal_id == id) return true;
          if (std::chrono::steady_clock::now() - last_sent > std::chrono::seconds(1)) {
            bus_.Publish(ch::ForRobot(kRobot, ch::kGoal), g);
            last_sent = std::chrono::steady_clock::now();
          }
          return false;
        },
        30.0, [&] { bus_.Pump(20); }))
        << "the navigator never took goal " << id << "\n"
        << navigator_->Log();
  }
  std::optional<cairn::lcmt_nav_status> Status() {
    return bus_.Last<cairn::lcmt_nav_status>(ch::ForRobot(kRobot, ch::kNavStatus));
  }
  std::vector<common::Pose2> Poses() {
    std::vector<common::Pose2> out;
    for (const auto& raw : bus_.Kept(ch::ForRobot(kRobot, ch::kPose))) {
      cairn::lcmt_pose p;
      if (p.decode(raw.data(), 0, static_cast<int>(raw.size())) < 0) continue;
      const Eigen::Quaterniond q(p.orientation_wxyz[0], p.orientation_wxyz[1],
                                 p.orientation_wxyz[2], p.orientation_wxyz[3]);
      const Eigen::Vector3d x = q * Eigen::Vector3d::UnitX();
      out.push_back({p.position_m[0], p.position_m[1], std::atan2(x.y(), x.x())});
    }
    return out;
  }

  ProcessSet procs_;
  Bus bus_;
  SonarTiles tiles_;
  testing::ChildProcess* mapper_{nullptr};
  testing::ChildProcess* navigator_{nullptr};
};

// Test 13: from (0, 0) to (35, 0) past four rocks. The AUV waits for its sonar to show water
// (explore first), goes only through water it has seen, ends within the 2 m tolerance, never
// touches a rock, and the sonar layer holds an occupied cluster at every rock.
TEST_F(UnderwaterStackTest, Seed004Test13RocksToTheGoalWithoutContact) {
  Start("4");
  SendGoal(13, 35.0, 0.0);
  const bool ended = WaitFor(
      [&] {
        auto s = Status();
        return s && s->goal_id == 13 && (s->state == kStateReached || s->state == kStateFailed);
      },
      400.0, [&] { bus_.Pump(20); });
  ASSERT_TRUE(ended) << "no end within 400 s\n" << navigator_->Log();
  ASSERT_EQ(Status()->state, kStateReached) << Status()->message << "\n" << navigator_->Log();
  // Let the last pose arrive, then judge the whole drive on ground truth.
  WaitFor([] { return false; }, 1.0, [&] { bus_.Pump(20); });
  const std::vector<common::Pose2> poses = Poses();
  ASSERT_GT(poses.size(), 100u);
  EXPECT_LE((poses.back().position() - Vector2(35.0, 0.0)).norm(), 2.0);
  const std::vector<Rock> rocks = RocksWorld();
  for (const Rock& rock : rocks) {
    double closest = 1e300;
    common::Pose2 where;
    for (const common::Pose2& p : poses) {
      const double c = HullClearance(rock, p);
      if (c < closest) {
        closest = c;
        where = p;
      }
    }
    EXPECT_GT(closest, 0.0) << "the hull touched " << rock.name << " at (" << where.x_m << ", "
                            << where.y_m << ", " << where.yaw_rad << ")";
  }
  // The drive went through the velocity bridge: body-velocity requests, surge and yaw only.
  const auto& requests = bus_.Kept(ch::ForRobot(kRobot, ch::kBodyVelocity));
  ASSERT_FALSE(requests.empty());
  cairn::lcmt_body_velocity_request r;
  ASSERT_GE(r.decode(requests.back().data(), 0, static_cast<int>(requests.back().size())), 0);
  EXPECT_EQ(r.requester, "Twist2BVR");
  EXPECT_FALSE(r.disable_axis[0]);
  EXPECT_TRUE(r.disable_axis[1] && r.disable_axis[2] && r.disable_axis[3] && r.disable_axis[4]);
  EXPECT_FALSE(r.disable_axis[5]);
  EXPECT_FALSE(bus_.Seen(ch::ForRobot(kRobot, ch::kCmdVel)));
  // It waited for the sonar before it moved, and said so.
  EXPECT_NE(navigator_->Log().find("explore first: waiting for the map"), std::string::npos)
      << navigator_->Log();
  // Every rock is on the sonar layer.
  const auto map = tiles_.Layer();
  ASSERT_TRUE(map.has_value());
  const std::vector<Cluster> clusters = Clusters(*map);
  std::string listed;
  for (const Cluster& c : clusters) {
    listed += " (" + std::to_string(c.centre.x()) + ", " + std::to_string(c.centre.y()) +
              "): " + std::to_string(c.cells);
  }
  for (const Rock& rock : rocks) {
    int near = 0;
    for (const Cluster& c : clusters) near += (c.centre - rock.centre).norm() < 3.5;
    EXPECT_GE(near, 1) << rock.name << " is not on the sonar layer; clusters:" << listed;
  }
}

}  // namespace
}  // namespace cairn::planner
