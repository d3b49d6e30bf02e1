// cairn-mapstore: the map store on the bus. Thin: flags, parameters (LoadMapstoreParams), open
// the database, construct MapstoreService, spin.

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "common/flags.h"
#include "common/log.h"
#include "mapstore/lcm/mapstore_service.h"
#include "mapstore/mapping_deriver.h"
#include "mapstore/mapstore_params.h"
#include "mapstore/sqlite_map_store.h"
#include "services/runtime/node.h"

namespace {

namespace ms = cairn::mapstore;

// Maps arrive as bursts of tiles: a large receive buffer unless the URL names one (the kernel
// caps it at net.core.rmem_max; resend requests cover what a small one drops).
std::string BusUrl(const std::string& flag_url, int recv_buffer_bytes) {
  return cairn::runtime::WithReceiveBuffer(cairn::runtime::ResolveLcmUrl(flag_url),
                                           recv_buffer_bytes);
}

int Serve(const std::string& db, ms::SqliteMapStore& store, const ms::MapstoreParams& params,
          const std::string& url) {
  cairn::runtime::NodeOptions node_options;
  node_options.process_name = "cairn-mapstore";
  node_options.lcm_url = url;
  cairn::runtime::Node node(node_options);
  ms::MapstoreService service(node, store, ms::MappingDeriver(), params.service);
  // Saves do not pay for checkpoints: the WAL is copied into the file when the store is idle.
  node.AddTimer(1.0, [&store] { store.CheckpointIfIdle(2.0); });
  node.SetState(cairn::runtime::HealthState::kReady);
  node.Event("serving %s (schema %d, synchronous %s) on %s", db.c_str(), store.schema_version(),
             ms::SynchronousName(params.database.synchronous), node.url().c_str());
  if (!store.write_refusal().empty()) {
    // Loads go on; every save, share or profile put is refused, naming the file and the reason.
    CAIRN_LOG_ERROR("serving read-only, saves will fail: %s", store.write_refusal().c_str());
    node.Count("read_only");
  }
  node.Spin();
  node.SetState(cairn::runtime::HealthState::kStopping);
  if (service.running_jobs() > 0 || service.pending_saves() > 0) {
    // Do not wait for a long derivation: the database is consistent at every instant (what
    // was not committed is simply not there), so leave now.
    node.Event("stopping with %lld requests unfinished",
               static_cast<long long>(service.running_jobs() + service.pending_saves()));
    std::fflush(nullptr);
    std::_Exit(0);
  }
  node.Event("stopping");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string db = "var/cairn.db";
  std::string config;
  std::string lcm_url;
  std::string files_root;
  int recv_buffer_bytes = 4 << 20;
  cairn::common::FlagParser flags(
      "cairn-mapstore",
      "Keeps maps for every robot profile in one SQLite file and serves them over LCM: save "
      "(push or pull from a mapper), load for a profile, list, share with another profile, "
      "delete, export, import.");
  flags.AddString("db", &db, "SQLite database file (created when missing)");
  flags.AddString("config", &config, "YAML parameters (see config/mapstore/mapstore.yaml)");
  flags.AddString("files-root", &files_root,
                  "folder that OP_EXPORT/OP_IMPORT paths are relative to (overrides the config)");
  flags.AddString("lcm-url", &lcm_url, "LCM URL (default: LCM_DEFAULT_URL or udpm ttl=0)");
  flags.AddInt("recv-buffer-bytes", &recv_buffer_bytes,
               "UDP receive buffer asked for when the URL names none (capped by the kernel)");
  flags.AddHelpSection(
      "Channels",
      "in:  MAPSTORE.REQUEST, MAPSTORE.TILE_RESEND, MAPSTORE.PUSH.{TILES,MANIFEST,OBSTACLES,"
      "OCTOMAP}, <robot>.MAP.{TILES,OCCUPANCY,MANIFEST,OBSTACLES,OCTOMAP} (pull saves)\n"
      "out: MAPSTORE.REPLY, MAPSTORE.{TILES,TILE_BATCHES,MANIFEST,OCTOMAP}, "
      "MAPSTORE.PUSH.TILE_RESEND, "
      "<robot>.MAP.{CONTROL,TILE_RESEND}, HEALTH");
  const int rc = flags.Parse(argc, argv);
  if (rc >= 0) return rc;
  cairn::common::SetLogTag("cairn-mapstore");

  ms::MapstoreParams params;
  try {
    if (!config.empty()) params = ms::LoadMapstoreParamsFile(config);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn-mapstore: %s\n", e.what());
    return 2;
  }
  if (!files_root.empty()) params.service.files_root = files_root;

  std::error_code ec;
  const auto parent = std::filesystem::path(db).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  auto store = ms::SqliteMapStore::Open(db, params.database);
  if (!store.ok()) {
    CAIRN_LOG_ERROR("cannot open the map store: %s", store.status().ToString().c_str());
    return 1;
  }
  try {
    return Serve(db, **store, params, BusUrl(lcm_url, recv_buffer_bytes));
  } catch (const std::exception& e) {
    CAIRN_LOG_ERROR("%s", e.what());
    return 1;
  }
}
