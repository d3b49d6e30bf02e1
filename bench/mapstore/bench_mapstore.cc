// bench_mapstore: the map store through the service, real LCM between processes.
//
// Starts cairn-mapstore on a private bus and a fresh database, then measures from this process:
// - push save of a 1000 x 1000-cell map with four layers (target <= 100 ms), beside the same
//   save done in-process by SqliteMapStore (no bus);
// - load of those four layers (target <= 100 ms), beside the in-process load;
// - derivation for a new profile (share) beside a cached derived layer, through the service
//   and in the store core (target <= 5 ms);
// - database size per square kilometre at 0.2 m, beside raw float32.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <arpa/inet.h>
#include <fcntl.h>
#include <lcm/lcm-cpp.hpp>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cairn/lcmt_mapstore_request.hpp"

#include "bench/support/figure.h"
#include "common/flags.h"
#include "common/layers.h"
#include "common/robot_profile.h"
#include "mapstore/map_operations.h"
#include "mapstore/lcm/mapstore_client.h"
#include "mapstore/sqlite_map_store.h"
#include "services/runtime/conversions.h"
#include "mapstore/mapping_deriver.h"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using cairn::bench::Figure;
using cairn::bench::Report;
using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[v.size() / 2];
}

int FreePort() {
  int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  int port = 0;
  if (bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) == 0) {
    socklen_t len = sizeof(addr);
    getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
    port = ntohs(addr.sin_port);
  }
  close(fd);
  return port != 0 ? port : 20000 + getpid() % 20000;
}

// A 1000 x 1000 map at 0.2 m like a mapper's: smooth hills with 1 cm noise and a 10 degree ramp,
// variance, observation counts and occupancy log-odds, 10 % never seen. Seeded.
cairn::mapstore::MapSnapshot MakeMap(int size, uint32_t seed, float offset) {
  using namespace cairn;
  mapstore::MapSnapshot s;
  s.site = "bench";
  s.name = "terrain";
  s.provenance.source_robot = "rover1";
  s.provenance.source_profile = "pioneer3at";
  s.provenance.code_version = "bench";
  common::GridGeometry g;
  g.resolution_m = 0.2;
  g.size_x = size;
  g.size_y = size;
  g.origin = {-100.0, -100.0, 0.0};
  s.base = common::GridMap(g);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.f, 0.01f);
  auto& e = s.base.AddLayer(layers::kElevation);
  auto& v = s.base.AddLayer(layers::kElevationVariance);
  auto& n = s.base.AddLayer(layers::kObservationCount);
  auto& o = s.base.AddLayer(layers::kOccupancyLogOdds);
  const float ramp = std::tan(10.f * static_cast<float>(M_PI) / 180.f) * 0.2f;
  for (int iy = 0; iy < size; ++iy) {
    for (int ix = 0; ix < size; ++ix) {
      const bool unseen = (ix / 50 + iy / 70) % 10 == 3;
      if (unseen) continue;
      float h = offset + 0.8f * std::sin(ix * 0.01f) * std::cos(iy * 0.013f);
      if (ix >= 400 && ix < 450 && iy >= 300 && iy < 360) h += (ix - 400) * ramp;
      e(ix, iy) = h + noise(rng);
      v(ix, iy) = 1e-4f + std::abs(noise(rng)) * 1e-3f;
      n(ix, iy) = static_cast<float>(1 + (ix * 7 + iy * 3) % 40);
      o(ix, iy) = (ix % 97 < 3 || iy % 89 < 2) ? 2.2f : -1.4f;
    }
  }
  return s;
}

cairn::common::RobotProfile LoadProfile(const std::string& name) {
  return cairn::common::LoadRobotProfileFile(std::string(CAIRN_SOURCE_DIR) + "/config/profiles/" +
                                             name + ".yaml");
}

}  // namespace

// A cached layer loads in a few milliseconds, where scheduling noise weighs: its figures are
// the median of this many loads per run.
constexpr int kCachedLoadsPerRun = 5;

int main(int argc, char** argv) {
  using namespace cairn;
  int size = 1000;
  int runs = 5;
  bool keep = false;
  common::FlagParser flags("bench_mapstore",
                           "Map store save/load/derive through cairn-mapstore over LCM.");
  flags.AddInt("size", &size, "cells per side of the map");
  flags.AddInt("runs", &runs, "repetitions per figure (the median is reported)");
  flags.AddBool("keep", &keep, "keep the benchmark database");
  int client_decode_threads = 0;
  flags.AddInt("client-decode-threads", &client_decode_threads,
               "threads the client decodes a batch of reply tiles on (0: its default)");
  int service_recv_buf_bytes = 0;
  flags.AddInt("service-recv-buf-bytes", &service_recv_buf_bytes,
               "the service's socket receive buffer (0: its own default, 4 MB capped by "
               "net.core.rmem_max; 212992 is Debian's default cap)");
  const int rc = flags.Parse(argc, argv);
  if (rc >= 0) return rc;
  const bench::StealNote steal_note;

  const fs::path dir = fs::path(CAIRN_BINARY_DIR) / "bench-tmp" / "mapstore";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string db = (dir / "bench.db").string();
  const std::string url = "udpm://239.255.76.67:" + std::to_string(FreePort()) + "?ttl=0";
  const std::string exe =
      (fs::canonical("/proc/self/exe").parent_path() / "cairn-mapstore").string();
  const std::string log = (dir / "cairn-mapstore.log").string();

  // The service, as its own process.
  pid_t pid = 0;
  {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    const std::string service_url =
        service_recv_buf_bytes > 0
            ? url + "&recv_buf_size=" + std::to_string(service_recv_buf_bytes)
            : url;
    std::vector<std::string> args = {exe, "--db", db, "--lcm-url", service_url};
    std::vector<char*> argv_c;
    for (auto& a : args) argv_c.push_back(a.data());
    argv_c.push_back(nullptr);
    if (posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv_c.data(), environ) != 0) {
      std::fprintf(stderr, "cannot start %s\n", exe.c_str());
      return 1;
    }
    posix_spawn_file_actions_destroy(&actions);
  }
  auto stop_service = [&] {
    kill(pid, SIGTERM);
    int status = 0;
    waitpid(pid, &status, 0);
  };

  lcm::LCM lcm(url);
  mapstore::MapstoreClientOptions client_options;
  if (client_decode_threads > 0) client_options.decode_threads = client_decode_threads;
  mapstore::MapstoreClient client(lcm, "bench_mapstore", client_options);
  // Wait until the service answers.
  {
    cairn::lcmt_mapstore_request ping{};
    ping.op = cairn::lcmt_mapstore_request::OP_LIST_PROFILES;
    auto reply = client.Call(ping);
    if (!reply.ok()) {
      std::fprintf(stderr, "cairn-mapstore did not answer: %s\n",
                   reply.status().ToString().c_str());
      stop_service();
      return 1;
    }
  }
  for (const char* name : {"pioneer3at", "rover"}) {
    cairn::lcmt_mapstore_request put{};
    put.op = cairn::lcmt_mapstore_request::OP_PUT_PROFILE;
    put.has_profile = true;
    put.profile_data = runtime::ToLcm(LoadProfile(name));
    client.Call(put);
  }

  // Saves and loads through the service.
  std::vector<double> save_ms, load_ms;
  int resends = 0;
  int64_t last_version = 0;
  for (int r = 0; r < runs; ++r) {
    const mapstore::MapSnapshot map = MakeMap(size, 1000 + r, 0.01f * r);
    const auto t0 = Clock::now();
    auto reply = client.Save(map);
    const double ms = Ms(t0);
    if (!reply.ok() || reply->status != 0) {
      std::fprintf(stderr, "save failed: %s\n",
                   reply.ok() ? reply->message.c_str() : reply.status().ToString().c_str());
      stop_service();
      return 1;
    }
    save_ms.push_back(ms);
    last_version = reply->version;
    const auto t1 = Clock::now();
    auto loaded = client.Load("bench", "terrain", last_version, "");
    const double lms = Ms(t1);
    if (!loaded.ok() || loaded->layers.layer_names().size() != 4) {
      std::fprintf(stderr, "load failed: %s\n", loaded.status().ToString().c_str());
      stop_service();
      return 1;
    }
    const common::Layer& got = loaded->layers.at(layers::kElevation);
    const common::Layer& sent = map.base.at(layers::kElevation);
    int64_t differing = 0;
    for (Eigen::Index i = 0; i < got.size(); ++i) {
      const float a = got.data()[i], b = sent.data()[i];
      differing += !(std::isnan(a) && std::isnan(b)) && a != b;
    }
    if (differing != 0) {
      std::fprintf(stderr, "loaded elevation differs from the saved one in %lld cells\n",
                   static_cast<long long>(differing));
      stop_service();
      return 1;
    }
    resends += loaded->resend_requests;
    load_ms.push_back(lms);
  }

  // Derivation for a new profile (share) beside the cached derived layer.
  double derive_ms = NAN;
  std::vector<double> cached_ms;
  {
    cairn::lcmt_mapstore_request share{};
    share.op = cairn::lcmt_mapstore_request::OP_SHARE;
    share.site = "bench";
    share.map_name = "terrain";
    share.version = last_version;
    share.profile = "rover";
    const auto t0 = Clock::now();
    mapstore::MapstoreClientOptions slow;
    slow.total_timeout_s = 1800.0;  // derivation of a large map may take long
    mapstore::MapstoreClient patient(lcm, "bench_mapstore", slow);
    auto reply = patient.Call(share);
    derive_ms = Ms(t0);
    if (!reply.ok() || reply->status != 0) {
      std::fprintf(stderr, "share failed: %s\n",
                   reply.ok() ? reply->message.c_str() : reply.status().ToString().c_str());
      derive_ms = NAN;
    } else {
      for (int r = 0; r < kCachedLoadsPerRun * runs; ++r) {
        const auto t1 = Clock::now();
        auto loaded = client.Load("bench", "terrain", last_version, "rover", {"cost/rover"});
        if (loaded.ok()) cached_ms.push_back(Ms(t1));
      }
    }
  }
  stop_service();

  // The same work in-process, without the bus: the baselines.
  std::vector<double> core_save_ms, core_load_ms, core_cached_ms;
  int64_t base_bytes = 0;
  {
    auto store = mapstore::SqliteMapStore::Open((dir / "core.db").string());
    if (!store.ok()) return 1;
    for (int r = 0; r < runs; ++r) {
      const mapstore::MapSnapshot map = MakeMap(size, 1000 + r, 0.01f * r);
      const auto t0 = Clock::now();
      auto info = (*store)->SaveMap(map, {"bench", 0, 0});
      core_save_ms.push_back(Ms(t0));
      const auto t1 = Clock::now();
      auto layers = (*store)->LoadLayers({"bench", "terrain", info->version}, {});
      core_load_ms.push_back(Ms(t1));
      base_bytes = (*store)->BaseBytes({"bench", "terrain", info->version}).value();
    }
    auto service_db = mapstore::SqliteMapStore::Open(db);
    if (service_db.ok()) {
      auto rover = (*service_db)->GetProfile("rover");
      for (int r = 0; r < kCachedLoadsPerRun * runs && rover.ok(); ++r) {
        const auto t0 = Clock::now();
        auto hit = (*service_db)
                       ->FindDerived({"bench", "terrain", last_version}, rover->content_hash,
                                     mapstore::MappingDeriver().code_version,
                                     {{"cost/rover"}, std::nullopt});
        if (hit.ok() && hit->has_value()) core_cached_ms.push_back(Ms(t0));
      }
    }
  }

  const double area_km2 = size * 0.2 * size * 0.2 / 1e6;
  const double mb_per_km2 = base_bytes / area_km2 / 1e6;
  const double raw_mb_per_km2 = 4.0 * 4.0 * (1.0 / (0.2 * 0.2)) * 1e6 / 1e6;  // 4 layers float32
  const std::string label = std::to_string(size) + "x" + std::to_string(size) + "x4";
  Report({"mapstore.save_" + label + ".via_service", Median(save_ms), "ms",
          "SqliteMapStore::SaveMap in-process (no bus)", Median(core_save_ms), false, "<= 100 ms",
          Median(save_ms) <= 100.0});
  Report({"mapstore.load_" + label + ".via_service", Median(load_ms), "ms",
          "SqliteMapStore::LoadLayers in-process (no bus)", Median(core_load_ms), false,
          "<= 100 ms", Median(load_ms) <= 100.0});
  Report({"mapstore.cached_cost_layer.via_service", Median(cached_ms), "ms",
          "derivation for a new profile (share, rover)", derive_ms, false, "<= 5 ms",
          Median(cached_ms) <= 5.0});
  Report({"mapstore.cached_cost_layer.store_core", Median(core_cached_ms), "ms",
          "derivation for a new profile (share, rover)", derive_ms, false, "<= 5 ms",
          Median(core_cached_ms) <= 5.0});
  Report({"mapstore.db_size_per_km2_at_0.2m", mb_per_km2, "MB/km2", "raw float32, 4 layers",
          raw_mb_per_km2, false, "reported", true});
  std::printf(
      "(load resend requests over %d runs: %d; cached layer figures: median of %zu and %zu loads; "
      "service log: %s)\n",
      runs, resends, cached_ms.size(), core_cached_ms.size(), log.c_str());
  if (!keep) {
    std::error_code ec;
    fs::remove(db, ec);
    fs::remove((dir / "core.db").string(), ec);
  }
  return 0;
}
