// bench_mapstore: the map store through the service, real LCM between processes.
//
// Starts cairn-mapstore on a private bus and a fresh database, then measures from this process:
// - push save of a 1000 x 1000-cell map with four layers (target <= 100 ms), beside the same
//   save done in-process by SqliteMapStore (no bus);
// - load of those four layers as a user meets them: cold, the first load of a version by a
//   store process started after it was saved, with the database file dropped from the OS page
//   cache (target <= 100 ms), beside the same cold load in-process; and, reported beside, the
//   warm load of the version saved a moment before (this benchmark's headline until issue 16);
// - derivation for a new profile (share) beside a cached derived layer, through the service
//   and in the store core (target <= 5 ms);
// - database size per square kilometre at 0.2 m, beside raw float32.
// A failed save or load is counted, printed, and enters its median as infinitely slow; the
// program exits 1 when any figure misses its target or anything failed.

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
#include "mapstore/lcm/mapstore_client.h"
#include "mapstore/map_operations.h"
#include "mapstore/mapping_deriver.h"
#include "mapstore/sqlite_map_store.h"
#include "services/runtime/conversions.h"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using namespace cairn;
using bench::Figure;
using bench::Report;
using Clock = std::chrono::steady_clock;

// A cached layer loads in a few milliseconds, where scheduling noise weighs: its figures are
// the median of this many loads per run.
constexpr int kCachedLoadsPerRun = 5;
constexpr char kColdMeaning[] =
    "cold = the first load of a version by a cairn-mapstore started after the version was "
    "saved, the database file dropped from the OS page cache (posix_fadvise DONTNEED) before "
    "it started; warm = the load of the version saved a moment before, by the process that "
    "saved it";

double Ms(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Timings of one figure; a failure counts as an infinitely slow sample.
struct Samples {
  std::vector<double> ms;
  int failed{0};
  void Add(double v) { ms.push_back(v); }
  void Fail(const std::string& what) {
    ++failed;
    ms.push_back(INFINITY);
    std::fprintf(stderr, "FAILED: %s\n", what.c_str());
  }
  double Median() const {
    std::vector<double> v = ms;
    std::sort(v.begin(), v.end());
    return v.empty() ? NAN : v[v.size() / 2];
  }
  std::string Count() const {
    return std::to_string(ms.size()) + (failed ? " (" + std::to_string(failed) + " failed)" : "");
  }
};

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
mapstore::MapSnapshot MakeMap(int size, uint32_t seed, float offset) {
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

// The map of run r (every run saves another version, with other content).
mapstore::MapSnapshot RunMap(int size, int r) { return MakeMap(size, 1000 + r, 0.01f * r); }

common::RobotProfile LoadProfile(const std::string& name) {
  return common::LoadRobotProfileFile(std::string(CAIRN_SOURCE_DIR) + "/config/profiles/" + name +
                                      ".yaml");
}

// Cells of the loaded elevation that differ from the saved one (NaN equals NaN).
int64_t DifferingCells(const common::GridMap& loaded, const common::GridMap& saved) {
  if (!loaded.HasLayer(layers::kElevation)) return -1;
  const common::Layer& got = loaded.at(layers::kElevation);
  const common::Layer& sent = saved.at(layers::kElevation);
  if (got.size() != sent.size()) return -1;
  int64_t differing = 0;
  for (Eigen::Index i = 0; i < got.size(); ++i) {
    const float a = got.data()[i], b = sent.data()[i];
    differing += !(std::isnan(a) && std::isnan(b)) && a != b;
  }
  return differing;
}

// Drops a database file (and its WAL) from the OS page cache, after writing it out.
void DropFromPageCache(const std::string& path) {
  for (const std::string& file : {path, path + "-wal", path + "-shm"}) {
    const int fd = open(file.c_str(), O_RDONLY);
    if (fd < 0) continue;
    fdatasync(fd);
    posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
    close(fd);
  }
}

// cairn-mapstore as its own process, its output appended to `log`.
class ServiceProcess {
 public:
  ServiceProcess(const std::string& db, const std::string& url, const std::string& log) {
    const std::string exe =
        (fs::canonical("/proc/self/exe").parent_path() / "cairn-mapstore").string();
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    std::vector<std::string> args = {exe, "--db", db, "--lcm-url", url};
    std::vector<char*> argv_c;
    for (auto& a : args) argv_c.push_back(a.data());
    argv_c.push_back(nullptr);
    if (posix_spawn(&pid_, exe.c_str(), &actions, nullptr, argv_c.data(), environ) != 0) {
      pid_ = 0;
    }
    posix_spawn_file_actions_destroy(&actions);
  }
  ~ServiceProcess() { Stop(); }
  ServiceProcess(const ServiceProcess&) = delete;
  ServiceProcess& operator=(const ServiceProcess&) = delete;
  bool started() const { return pid_ != 0; }
  void Stop() {
    if (pid_ == 0) return;
    kill(pid_, SIGTERM);
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = 0;
  }

 private:
  pid_t pid_{0};
};

// Waits until the service answers.
bool Answers(mapstore::MapstoreClient& client) {
  cairn::lcmt_mapstore_request ping{};
  ping.op = cairn::lcmt_mapstore_request::OP_LIST_PROFILES;
  auto reply = client.Call(ping);
  if (!reply.ok()) {
    std::fprintf(stderr, "cairn-mapstore did not answer: %s\n", reply.status().ToString().c_str());
  }
  return reply.ok();
}

struct Options {
  int size{1000};
  int runs{5};
  bool keep{false};
  int client_decode_threads{0};
  int service_recv_buf_bytes{0};
};

struct Figures {
  Samples save, warm_load, cold_load, cached;
  Samples core_save, core_warm_load, core_cold_load, core_cached;
  Samples core_save_full;  // the same saves with database.synchronous: full
  double derive_ms{NAN};
  int64_t base_bytes{0};
  int resends{0};
  int64_t last_version{0};
};

// Loads version `version` and checks its elevation against run r's map.
void TimedLoad(mapstore::MapstoreClient& client, const Options& o, int r, int64_t version,
               Samples* out, int* resends) {
  const auto t0 = Clock::now();
  auto loaded = client.Load("bench", "terrain", version, "");
  const double ms = Ms(t0);
  const std::string what = "load of version " + std::to_string(version);
  if (!loaded.ok()) return out->Fail(what + ": " + loaded.status().ToString());
  if (loaded->layers.layer_names().size() != 4) return out->Fail(what + ": not 4 layers");
  const int64_t differing = DifferingCells(loaded->layers, RunMap(o.size, r).base);
  if (differing != 0) {
    return out->Fail(what + ": elevation differs in " + std::to_string(differing) + " cells");
  }
  *resends += loaded->resend_requests;
  out->Add(ms);
}

// Through the first service process: saves, each followed by its warm load; then the share and
// the cached layer's loads.
void SavesAndWarmLoads(mapstore::MapstoreClient& client, lcm::LCM& lcm, const Options& o,
                       Figures* f) {
  for (const char* name : {"pioneer3at", "rover"}) {
    cairn::lcmt_mapstore_request put{};
    put.op = cairn::lcmt_mapstore_request::OP_PUT_PROFILE;
    put.has_profile = true;
    put.profile_data = runtime::ToLcm(LoadProfile(name));
    client.Call(put);
  }
  for (int r = 0; r < o.runs; ++r) {
    const mapstore::MapSnapshot map = RunMap(o.size, r);
    const auto t0 = Clock::now();
    auto reply = client.Save(map);
    const double ms = Ms(t0);
    if (!reply.ok() || reply->status != 0 || reply->version != r + 1) {
      f->save.Fail("save " + std::to_string(r + 1) + ": " +
                   (reply.ok() ? reply->message : reply.status().ToString()));
      continue;
    }
    f->save.Add(ms);
    f->last_version = reply->version;
    TimedLoad(client, o, r, reply->version, &f->warm_load, &f->resends);
  }
  cairn::lcmt_mapstore_request share{};
  share.op = cairn::lcmt_mapstore_request::OP_SHARE;
  share.site = "bench";
  share.map_name = "terrain";
  share.version = f->last_version;
  share.profile = "rover";
  mapstore::MapstoreClientOptions slow;
  slow.total_timeout_s = 1800.0;  // derivation of a large map may take long
  mapstore::MapstoreClient patient(lcm, "bench_mapstore", slow);
  const auto t0 = Clock::now();
  auto reply = patient.Call(share);
  f->derive_ms = Ms(t0);
  if (!reply.ok() || reply->status != 0) {
    f->derive_ms = NAN;
    f->cached.Fail("share: " + (reply.ok() ? reply->message : reply.status().ToString()));
    return;
  }
  for (int r = 0; r < kCachedLoadsPerRun * o.runs; ++r) {
    const auto t1 = Clock::now();
    auto loaded = client.Load("bench", "terrain", f->last_version, "rover", {"cost/rover"});
    if (!loaded.ok()) {
      f->cached.Fail("cached cost/rover load: " + loaded.status().ToString());
    } else {
      f->cached.Add(Ms(t1));
    }
  }
}

// The same work in-process, without the bus: the baselines (saves and warm loads, then cold
// loads by a store opened afresh on a file dropped from the page cache, then the cached layer).
void CoreBaselines(const std::string& core_db, const std::string& service_db, const Options& o,
                   Figures* f) {
  {
    auto store = mapstore::SqliteMapStore::Open(core_db);
    if (!store.ok()) return f->core_save.Fail("open " + store.status().ToString());
    for (int r = 0; r < o.runs; ++r) {
      const mapstore::MapSnapshot map = RunMap(o.size, r);
      const auto t0 = Clock::now();
      auto info = (*store)->SaveMap(map, {"bench", 0, 0});
      if (!info.ok()) {
        f->core_save.Fail("core save: " + info.status().ToString());
        continue;
      }
      f->core_save.Add(Ms(t0));
      const auto t1 = Clock::now();
      auto layers = (*store)->LoadLayers({"bench", "terrain", info->version}, {});
      if (layers.ok()) {
        f->core_warm_load.Add(Ms(t1));
      } else {
        f->core_warm_load.Fail("core warm load: " + layers.status().ToString());
      }
      auto bytes = (*store)->BaseBytes({"bench", "terrain", info->version});
      if (bytes.ok()) f->base_bytes = *bytes;
    }
  }
  {
    // The price of durability against power cuts: one fsync of the WAL per commit.
    mapstore::SqliteOptions full;
    full.synchronous = mapstore::Synchronous::kFull;
    auto store = mapstore::SqliteMapStore::Open(core_db + ".full", full);
    if (!store.ok()) return f->core_save_full.Fail("open " + store.status().ToString());
    for (int r = 0; r < o.runs; ++r) {
      const mapstore::MapSnapshot map = RunMap(o.size, r);
      const auto t0 = Clock::now();
      auto info = (*store)->SaveMap(map, {"bench", 0, 0});
      if (!info.ok()) {
        f->core_save_full.Fail("core save (synchronous full): " + info.status().ToString());
        continue;
      }
      f->core_save_full.Add(Ms(t0));
    }
  }
  DropFromPageCache(core_db);
  auto cold = mapstore::SqliteMapStore::Open(core_db);
  for (int r = 0; r < o.runs && cold.ok(); ++r) {
    const auto t0 = Clock::now();
    auto layers = (*cold)->LoadLayers({"bench", "terrain", r + 1}, {});
    if (layers.ok()) {
      f->core_cold_load.Add(Ms(t0));
    } else {
      f->core_cold_load.Fail("core cold load: " + layers.status().ToString());
    }
  }
  auto service = mapstore::SqliteMapStore::Open(service_db);
  auto rover = service.ok() ? (*service)->GetProfile("rover") : common::NotFoundError("no db");
  for (int r = 0; r < kCachedLoadsPerRun * o.runs; ++r) {
    if (!rover.ok()) return f->core_cached.Fail("core cached layer: " + rover.status().ToString());
    const auto t0 = Clock::now();
    auto hit = (*service)->FindDerived({"bench", "terrain", f->last_version}, rover->content_hash,
                                       mapstore::MappingDeriver().code_version,
                                       {{"cost/rover"}, std::nullopt});
    if (hit.ok() && hit->has_value()) {
      f->core_cached.Add(Ms(t0));
    } else {
      f->core_cached.Fail("core cached layer: not in the cache");
    }
  }
}

// Reports every figure; returns whether all met their targets.
bool ReportAll(const Options& o, const Figures& f) {
  const double area_km2 = o.size * 0.2 * o.size * 0.2 / 1e6;
  const double mb_per_km2 = f.base_bytes / area_km2 / 1e6;
  const double raw_mb_per_km2 = 4.0 * 4.0 * (1.0 / (0.2 * 0.2)) * 1e6 / 1e6;  // 4 layers float32
  const std::string label = std::to_string(o.size) + "x" + std::to_string(o.size) + "x4";
  const std::vector<Figure> figures = {
      {"mapstore.save_" + label + ".via_service", f.save.Median(), "ms",
       "SqliteMapStore::SaveMap in-process (no bus)", f.core_save.Median(), false, "<= 100 ms",
       f.save.Median() <= 100.0},
      {"mapstore.load_" + label + ".via_service", f.cold_load.Median(), "ms",
       "SqliteMapStore::LoadLayers in-process, cold", f.core_cold_load.Median(), false,
       "<= 100 ms (cold)", f.cold_load.Median() <= 100.0},
      {"mapstore.load_" + label + ".via_service_warm", f.warm_load.Median(), "ms",
       "SqliteMapStore::LoadLayers in-process, warm", f.core_warm_load.Median(), false,
       "reported (the headline before issue 16)", f.warm_load.failed == 0},
      {"mapstore.cached_cost_layer.via_service", f.cached.Median(), "ms",
       "derivation for a new profile (share, rover)", f.derive_ms, false, "<= 5 ms",
       f.cached.Median() <= 5.0},
      {"mapstore.cached_cost_layer.store_core", f.core_cached.Median(), "ms",
       "derivation for a new profile (share, rover)", f.derive_ms, false, "<= 5 ms",
       f.core_cached.Median() <= 5.0},
      {"mapstore.save_" + label + ".store_core_synchronous_full", f.core_save_full.Median(), "ms",
       "SqliteMapStore::SaveMap in-process, synchronous normal", f.core_save.Median(), false,
       "reported (durability against power cuts)", f.core_save_full.failed == 0},
      {"mapstore.db_size_per_km2_at_0.2m", mb_per_km2, "MB/km2", "raw float32, 4 layers",
       raw_mb_per_km2, false, "reported", f.base_bytes > 0},
  };
  bool all = true;
  for (const Figure& figure : figures) {
    Report(figure);
    all &= figure.pass;
  }
  return all;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  common::FlagParser flags("bench_mapstore",
                           "Map store save/load/derive through cairn-mapstore over LCM. Exit "
                           "status 1 when a figure misses its target or a save or load failed.");
  flags.AddInt("size", &o.size, "cells per side of the map");
  flags.AddInt("runs", &o.runs, "repetitions per figure (the median is reported)");
  flags.AddBool("keep", &o.keep, "keep the benchmark database");
  flags.AddInt("client-decode-threads", &o.client_decode_threads,
               "threads the client decodes a batch of reply tiles on (0: its default)");
  flags.AddInt("service-recv-buf-bytes", &o.service_recv_buf_bytes,
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
  const std::string service_url =
      o.service_recv_buf_bytes > 0
          ? url + "&recv_buf_size=" + std::to_string(o.service_recv_buf_bytes)
          : url;
  const std::string log = (dir / "cairn-mapstore.log").string();

  lcm::LCM lcm(url);
  mapstore::MapstoreClientOptions client_options;
  if (o.client_decode_threads > 0) client_options.decode_threads = o.client_decode_threads;
  mapstore::MapstoreClient client(lcm, "bench_mapstore", client_options);
  Figures f;
  {
    ServiceProcess service(db, service_url, log);
    if (!service.started() || !Answers(client)) return 1;
    SavesAndWarmLoads(client, lcm, o, &f);
  }
  // A store process started afresh, on a file out of the page cache: loads as users meet them.
  DropFromPageCache(db);
  {
    ServiceProcess service(db, service_url, log);
    if (!service.started() || !Answers(client)) return 1;
    for (int r = 0; r < o.runs; ++r) TimedLoad(client, o, r, r + 1, &f.cold_load, &f.resends);
  }
  CoreBaselines((dir / "core.db").string(), db, o, &f);

  const bool met = ReportAll(o, f);
  const int failures = f.save.failed + f.warm_load.failed + f.cold_load.failed + f.cached.failed +
                       f.core_save.failed + f.core_warm_load.failed + f.core_cold_load.failed +
                       f.core_cached.failed;
  std::printf("(%s)\n", kColdMeaning);
  std::printf(
      "(samples: saves %s, cold loads %s, warm loads %s, cached layer %s and %s in the core; "
      "failures enter a median as infinitely slow; load resend requests: %d; service log: %s)\n",
      f.save.Count().c_str(), f.cold_load.Count().c_str(), f.warm_load.Count().c_str(),
      f.cached.Count().c_str(), f.core_cached.Count().c_str(), f.resends, log.c_str());
  std::printf("bench_mapstore: %d failures, %s\n", failures,
              met ? "every target met" : "a target missed");
  if (!o.keep) {
    std::error_code ec;
    fs::remove(db, ec);
    fs::remove((dir / "core.db").string(), ec);
  }
  return failures == 0 && met ? 0 : 1;
}
