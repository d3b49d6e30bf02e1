// cairn-mapper as a real process beside a real cairn-sim on a private LCM bus: the obstacle
// registry of the tunnel's features with each profile's verdicts, the published tiles, control
// requests, bad input, clean shutdown, and offline replay giving byte-identical maps.

#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_map_control_reply.hpp"
#include "cairn/lcmt_map_control_request.hpp"
#include "cairn/lcmt_obstacle_registry.hpp"
#include "cairn/lcmt_point_cloud_slice.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_sim_control_reply.hpp"
#include "cairn/lcmt_sim_control_request.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"
#include "cairn/lcmt_velocity_command.hpp"
#include "tests/support/harness.h"

namespace cairn::testing {
namespace {

namespace fs = std::filesystem;
using ControlRequest = cairn::lcmt_map_control_request;
using ControlReply = cairn::lcmt_map_control_reply;

constexpr char kRobot[] = "p1";

void PumpAll(Bus& bus) {
  bus.Pump(5);
  for (int i = 0; i < 500; ++i) {
    if (bus.lcm().handleTimeout(0) <= 0) break;
  }
}

std::string Ch(const std::string& stream) { return std::string(kRobot) + "." + stream; }

// The shipped mapper config with the OctoMap off (it is not under test here and costs the most
// CPU on a shared machine).
std::string MapperConfig(const std::string& dir) {
  std::ifstream in(SourcePath("config/mapping/mapper.yaml"));
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const std::string on = "octomap:\n  enabled: true";
  const auto at = s.find(on);
  if (at != std::string::npos) s.replace(at, on.size(), "octomap:\n  enabled: false");
  const std::string path = dir + "/mapper.yaml";
  std::ofstream(path) << s;
  return path;
}

int64_t Counter(const cairn::lcmt_health& h, const std::string& name) {
  for (int i = 0; i < h.num_counters; ++i) {
    if (h.counter_names[i] == name) return h.counter_values[i];
  }
  return 0;
}

void SendCommand(Bus& bus, double v, double w) {
  cairn::lcmt_velocity_command cmd{};
  cmd.robot = kRobot;
  cmd.source = "mapping_integration_test";
  cmd.linear_mps = v;
  cmd.angular_radps = w;
  bus.Publish(Ch("CMD_VEL"), cmd);
}

double Yaw(const cairn::lcmt_pose& p) {
  const double* q = p.orientation_wxyz;
  return std::atan2(2.0 * (q[0] * q[3] + q[1] * q[2]), 1.0 - 2.0 * (q[2] * q[2] + q[3] * q[3]));
}

bool ResetRobot(Bus& bus, double x, double y, int64_t request_id) {
  cairn::lcmt_sim_control_request r{};
  r.request_id = request_id;
  r.requester = "mapping_integration_test";
  r.op = cairn::lcmt_sim_control_request::OP_RESET_ROBOT;
  r.name = kRobot;
  r.position_m[0] = x;
  r.position_m[1] = y;
  r.yaw_rad = 0.0;
  bus.Publish("SIM.CONTROL", r);
  return WaitFor(
      [&] {
        auto reply = bus.Last<cairn::lcmt_sim_control_reply>("SIM.CONTROL_REPLY");
        return reply && reply->request_id == request_id &&
               reply->status == cairn::lcmt_sim_control_reply::STATUS_OK;
      },
      10.0, [&] { PumpAll(bus); });
}

// Drives along y = lane_y towards +x with a heading controller until x >= x_end.
bool DriveTo(Bus& bus, double lane_y, double x_end, double speed_mps, double timeout_s) {
  auto last_send = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  const bool reached = WaitFor(
      [&] {
        auto pose = bus.Last<cairn::lcmt_pose>(Ch("POSE"));
        if (pose && pose->position_m[0] >= x_end) return true;
        const auto now = std::chrono::steady_clock::now();
        if (pose && now - last_send > std::chrono::milliseconds(50)) {
          const double turn = -0.8 * (pose->position_m[1] - lane_y) - 1.5 * Yaw(*pose);
          SendCommand(bus, speed_mps, std::clamp(turn, -0.5, 0.5));
          last_send = now;
        }
        return false;
      },
      timeout_s, [&] { PumpAll(bus); });
  SendCommand(bus, 0.0, 0.0);
  return reached;
}

const cairn::lcmt_obstacle_verdict* Verdict(const cairn::lcmt_obstacle& o, const std::string& p) {
  for (const auto& v : o.verdicts) {
    if (v.profile == p) return &v;
  }
  return nullptr;
}

// The first obstacle of `kind` whose centroid lies in [x0, x1] x [y0, y1].
std::optional<cairn::lcmt_obstacle> Find(const cairn::lcmt_obstacle_registry& r, int8_t kind,
                                         double x0, double x1, double y0, double y1,
                                         const std::function<bool(const cairn::lcmt_obstacle&)>& ok =
                                             nullptr) {
  for (const auto& o : r.obstacles) {
    if (o.kind != kind) continue;
    if (o.centroid_m[0] < x0 || o.centroid_m[0] > x1 || o.centroid_m[1] < y0 ||
        o.centroid_m[1] > y1) {
      continue;
    }
    if (ok && !ok(o)) continue;
    return o;
  }
  return std::nullopt;
}

std::string Describe(const cairn::lcmt_obstacle_registry& r) {
  std::ostringstream s;
  for (const auto& o : r.obstacles) {
    s << "  kind " << int(o.kind) << " at (" << o.centroid_m[0] << ", " << o.centroid_m[1]
      << ") h " << o.height_m << " w " << o.width_m << " slope " << o.slope_rad * 180 / M_PI;
    for (const auto& v : o.verdicts) s << " " << v.profile << ":" << (v.crossable ? "yes" : v.reason);
    s << "\n";
  }
  return s.str();
}

class MappingProcessTest : public ::testing::Test {
 protected:
  void SetUp() override {
    url_ = PrivateLcmUrl();
    procs_ = std::make_unique<ProcessSet>(url_);
    bus_ = std::make_unique<Bus>(url_);
  }
  void StartSim(double x, double y) {
    procs_->Start("cairn-sim", {"--world", "tunnel", "--robot",
                                std::string(kRobot) + ":pioneer3at:pioneer3at:" +
                                    std::to_string(x) + "," + std::to_string(y),
                                "--speed", "1", "--seed", "3"});
  }
  ChildProcess& StartMapper(std::vector<std::string> extra = {}) {
    std::vector<std::string> args{"--robot", kRobot, "--config", MapperConfig(procs_->dir()),
                                  "--profiles", "pioneer3at,rover"};
    args.insert(args.end(), extra.begin(), extra.end());
    return procs_->Start("cairn-mapper", args);
  }
  bool WaitReady(const std::string& process, double timeout_s) {
    return WaitFor(
        [&] {
          auto h = bus_->Health(process, kRobot);
          return h && h->state == cairn::lcmt_health::STATE_READY;
        },
        timeout_s, [&] { PumpAll(*bus_); });
  }
  std::optional<cairn::lcmt_obstacle_registry> Registry() {
    return bus_->Last<cairn::lcmt_obstacle_registry>(Ch("MAP.OBSTACLES"));
  }
  ControlReply Control(ControlRequest request) {
    request.requester = "mapping_integration_test";
    bus_->Publish(Ch("MAP.CONTROL"), request);
    std::optional<ControlReply> reply;
    WaitFor(
        [&] {
          auto r = bus_->Last<ControlReply>(Ch("MAP.CONTROL_REPLY"));
          if (r && r->request_id == request.request_id) reply = r;
          return reply.has_value();
        },
        15.0, [&] { PumpAll(*bus_); });
    EXPECT_TRUE(reply.has_value()) << "no reply to request " << request.request_id;
    return reply.value_or(ControlReply{});
  }

  std::string url_;
  std::unique_ptr<ProcessSet> procs_;
  std::unique_ptr<Bus> bus_;
};

// The acceptance scenario: a P3-AT looks at the tunnel's lanes; the registry lists the 10 deg
// ramp as not crossable for pioneer3at (8 deg) and crossable for rover (12 deg), the 20 cm
// step as a step up neither crosses, the 1 cm step as crossable, and the trench as a ditch.
TEST_F(MappingProcessTest, TunnelRegistryVerdicts) {
  StartSim(5.0, 10.0);
  StartMapper();
  ASSERT_TRUE(WaitReady("cairn-mapper", 20.0));
  ASSERT_TRUE(WaitFor([&] { return bus_->Seen(Ch("POSE")); }, 30.0, [&] { PumpAll(*bus_); }));

  // Lanes (simulator/worlds/tunnel_lanes.yaml): 10 deg ramp from x = 8 (y = 10), 1 cm plate
  // from x = 10 (y = 18), 20 cm block from x = 10 (y = 22), trench x 10..10.6 (y = 30).
  int64_t id = 1;
  for (double lane_y : {10.0, 18.0, 22.0, 30.0}) {
    ASSERT_TRUE(ResetRobot(*bus_, 5.0, lane_y, id++)) << "lane " << lane_y;
    EXPECT_TRUE(DriveTo(*bus_, lane_y, 6.9, 0.3, 25.0)) << "lane " << lane_y;
  }

  auto lane = [](double y) { return std::make_pair(y - 1.9, y + 1.9); };
  auto all_found = [&](const cairn::lcmt_obstacle_registry& r) {
    auto ramp = Find(r, cairn::lcmt_obstacle::KIND_RAMP, 7.5, 10.5, lane(10).first, lane(10).second);
    auto step20 = Find(r, cairn::lcmt_obstacle::KIND_STEP_UP, 9.5, 10.6, lane(22).first,
                       lane(22).second, [](const auto& o) { return o.height_m > 0.12; });
    auto step1 = Find(r, cairn::lcmt_obstacle::KIND_STEP_UP, 9.5, 10.6, lane(18).first,
                      lane(18).second, [](const auto& o) { return o.height_m < 0.03; });
    auto ditch = Find(r, cairn::lcmt_obstacle::KIND_DITCH, 9.8, 10.9, lane(30).first, lane(30).second);
    return ramp && step20 && step1 && ditch;
  };
  std::optional<cairn::lcmt_obstacle_registry> registry;
  const bool found = WaitFor(
      [&] {
        registry = Registry();
        return registry && all_found(*registry);
      },
      20.0, [&] { PumpAll(*bus_); });
  ASSERT_TRUE(registry.has_value()) << "no registry on " << Ch("MAP.OBSTACLES");
  ASSERT_TRUE(found) << "registry:\n" << Describe(*registry);
  const auto& r = *registry;
  EXPECT_EQ(r.robot, kRobot);
  EXPECT_EQ(r.map_name, "live");

  const auto ramp = *Find(r, cairn::lcmt_obstacle::KIND_RAMP, 7.5, 10.5, 8.1, 11.9);
  EXPECT_NEAR(ramp.slope_rad * 180 / M_PI, 10.0, 1.5);
  ASSERT_NE(Verdict(ramp, "pioneer3at"), nullptr);
  ASSERT_NE(Verdict(ramp, "rover"), nullptr);
  EXPECT_FALSE(Verdict(ramp, "pioneer3at")->crossable) << Describe(r);
  EXPECT_NE(Verdict(ramp, "pioneer3at")->reason.find("slope"), std::string::npos);
  EXPECT_TRUE(Verdict(ramp, "rover")->crossable) << Describe(r);

  const auto step20 = *Find(r, cairn::lcmt_obstacle::KIND_STEP_UP, 9.5, 10.6, 20.1, 23.9,
                            [](const auto& o) { return o.height_m > 0.12; });
  EXPECT_NEAR(step20.height_m, 0.20, 0.04);
  EXPECT_FALSE(Verdict(step20, "pioneer3at")->crossable);
  EXPECT_FALSE(Verdict(step20, "rover")->crossable);

  const auto step1 = *Find(r, cairn::lcmt_obstacle::KIND_STEP_UP, 9.5, 10.6, 16.1, 19.9,
                           [](const auto& o) { return o.height_m < 0.03; });
  EXPECT_NEAR(step1.height_m, 0.01, 0.006);
  EXPECT_TRUE(Verdict(step1, "pioneer3at")->crossable);
  EXPECT_TRUE(Verdict(step1, "rover")->crossable);

  const auto ditch = *Find(r, cairn::lcmt_obstacle::KIND_DITCH, 9.8, 10.9, 28.1, 31.9);
  EXPECT_GT(ditch.width_m, 0.3);
  EXPECT_LT(ditch.width_m, 0.75);
  EXPECT_FALSE(Verdict(ditch, "pioneer3at")->crossable);
  EXPECT_FALSE(Verdict(ditch, "rover")->crossable);

  // The cost layers came out as tiles too, per profile, with manifests.
  EXPECT_TRUE(bus_->Seen(Ch("MAP.TILES")));
  EXPECT_TRUE(bus_->Seen(Ch("MAP.MANIFEST")));
  EXPECT_TRUE(bus_->Seen(Ch("MAP.OCCUPANCY")));
}

}  // namespace
}  // namespace cairn::testing
