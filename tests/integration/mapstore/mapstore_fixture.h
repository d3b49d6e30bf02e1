#pragma once

// Helpers for the map store integration tests: real cairn-mapstore and cairn-map processes on a
// private bus.

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <sys/wait.h>

#include "cairn/lcmt_mapstore_request.hpp"

#include "common/layers.h"
#include "common/robot_profile.h"
#include "mapstore/map_store.h"
#include "mapstore/lcm/mapstore_client.h"
#include "services/runtime/conversions.h"
#include "tests/support/harness.h"
#include "tests/support/layers.h"

namespace cairn::mapstore::testing {

using cairn::testing::BinPath;
using cairn::testing::ChildProcess;
using cairn::testing::ProcessSet;
using cairn::testing::SourcePath;
using cairn::testing::WaitFor;
using Request = cairn::lcmt_mapstore_request;
using Reply = cairn::lcmt_mapstore_reply;

// Copies of the generated constants (gtest takes arguments by reference, and the generated
// classes only declare their constants).
constexpr int8_t kStatusOk = Reply::STATUS_OK;
constexpr int8_t kStatusNotFound = Reply::STATUS_NOT_FOUND;
constexpr int8_t kStatusInvalid = Reply::STATUS_INVALID;

/// A request with every field defined.
inline Request MakeRequest(int8_t op, const std::string& site = "", const std::string& map = "",
                           int64_t version = 0) {
  Request r{};
  r.op = op;
  r.site = site;
  r.map_name = map;
  r.version = version;
  r.has_profile = false;
  r.expect_obstacles = false;
  r.expect_octomap = false;
  return r;
}

/// Waits until a cairn-mapstore on the client's bus answers.
inline bool WaitForStore(MapstoreClient& client, double timeout_s = 20.0) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    auto reply = client.Call(MakeRequest(Request::OP_LIST_PROFILES));
    if (reply.ok()) return true;
  }
  return false;
}

/// Client options for tests: short per-attempt timeouts, bounded total.
inline MapstoreClientOptions TestClientOptions(double total_s = 30.0) {
  MapstoreClientOptions o;
  o.reply_timeout_s = 1.0;
  o.total_timeout_s = total_s;
  return o;
}

inline common::RobotProfile ShippedProfile(const std::string& name) {
  return common::LoadRobotProfileFile(SourcePath("config/profiles/" + name + ".yaml"));
}

inline Request PutProfileRequest(const common::RobotProfile& profile) {
  Request r = MakeRequest(Request::OP_PUT_PROFILE);
  r.has_profile = true;
  r.profile_data = runtime::ToLcm(profile);
  return r;
}

/// Result of a cairn-map run.
struct CliResult {
  int exit_code{-1};
  std::string output;  ///< stdout and stderr
};

/// Runs build/bin/cairn-map with args; waits at most timeout_s.
inline CliResult RunCli(ProcessSet& set, std::vector<std::string> args, double timeout_s = 60.0) {
  std::vector<std::string> argv = {BinPath("cairn-map")};
  argv.insert(argv.end(), args.begin(), args.end());
  ChildProcess& p = set.StartRaw("cairn-map", argv);
  CliResult r;
  if (auto status = p.WaitExit(timeout_s)) {
    r.exit_code = WIFEXITED(*status) ? WEXITSTATUS(*status) : 128 + WTERMSIG(*status);
  }
  r.output = p.Log();
  return r;
}

/// A map as a mapper leaves it: elevation with known features, variance and counts, seeded.
inline MapSnapshot TerrainSnapshot(const std::string& site, const std::string& name, int size_x,
                                   int size_y, float offset) {
  MapSnapshot s;
  s.site = site;
  s.name = name;
  s.provenance.source_robot = "rover1";
  s.provenance.source_profile = "pioneer3at";
  s.provenance.code_version = "test";
  s.provenance.parameters = "resolution_m: 0.2\n";
  common::GridGeometry g;
  g.resolution_m = 0.2;
  g.size_x = size_x;
  g.size_y = size_y;
  g.origin = {-3.0, -2.0, 0.0};
  s.base = common::GridMap(g);
  auto& e = s.base.AddLayer(layers::kElevation);
  auto& v = s.base.AddLayer(layers::kElevationVariance);
  for (int iy = 0; iy < size_y; ++iy) {
    for (int ix = 0; ix < size_x; ++ix) {
      e(ix, iy) = offset + 0.3f * std::sin(ix * 0.05f) * std::cos(iy * 0.07f);
      v(ix, iy) = 1e-4f + 1e-6f * static_cast<float>((ix * 31 + iy * 17) % 97);
    }
  }
  e(0, 0) = common::kUnknown;
  return s;
}

inline std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

using cairn::testing::SameLayer;

}  // namespace cairn::mapstore::testing
