// cairn-mapstore: the map store on the bus. Thin: flags, YAML parameters, open the database,
// construct MapstoreService, spin.

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "common/channels.h"
#include "common/flags.h"
#include "common/log.h"
#include "common/yaml_reader.h"
#include "mapstore/lcm/mapstore_service.h"
#include "mapstore/sqlite_map_store.h"
#include "services/runtime/node.h"
#include "mapstore/mapping_deriver.h"

namespace {

using cairn::common::YamlMap;

// Reads config/mapstore/mapstore.yaml (every key optional, unknown keys are errors).
void LoadParams(const std::string& path, cairn::mapstore::MapstoreServiceParams* service,
                cairn::mapstore::SqliteOptions* sqlite) {
  YamlMap root = YamlMap::LoadFile(path);
  if (root.Has("service")) {
    YamlMap s = root.Child("service");
    s.Get("files_root", &service->files_root);
    s.Get("save_timeout_s", &service->save_timeout_s);
    s.Get("resend_interval_s", &service->resend_interval_s);
    s.Get("staging_timeout_s", &service->staging_timeout_s);
    s.Get("pull_settle_s", &service->pull_settle_s);
    s.Get("reply_cache_size", &service->reply_cache_size);
    s.Get("max_kept_reply_cells", &service->max_kept_reply_cells);
    s.Get("max_staged_cells", &service->max_staged_cells);
    s.Get("reply_tile_size", &service->reply_tile_size);
    s.Get("max_reply_obstacles", &service->max_reply_obstacles);
    s.Get("tiles_per_burst", &service->tiles_per_burst);
    s.Get("batch_bytes", &service->batch_bytes);
    s.Get("burst_pause_ms", &service->burst_pause_ms);
    s.Get("worker_threads", &service->worker_threads);
    s.Get("decode_threads", &service->decode_threads);
    s.Get("compress_reply_tiles", &service->compress_reply_tiles);
    s.Finish();
  }
  if (root.Has("database")) {
    YamlMap d = root.Child("database");
    d.Get("busy_timeout_ms", &sqlite->busy_timeout_ms);
    d.Get("write_attempts", &sqlite->write_attempts);
    d.Get("synchronous_full", &sqlite->synchronous_full);
    d.Get("tile_size_cells", &sqlite->tile_size_cells);
    d.Get("zstd_level", &sqlite->zstd_level);
    d.Get("compression_threads", &sqlite->compression_threads);
    d.Get("cache_size_kib", &sqlite->cache_size_kib);
    d.Get("max_page_count", &sqlite->max_page_count);
    d.Get("wal_autocheckpoint_pages", &sqlite->wal_autocheckpoint_pages);
    d.Finish();
  }
  root.Finish();
  if (service->batch_bytes < 0 || service->batch_bytes > 200000) {
    root.Fail(root.Raw("service"),
              "service.batch_bytes must be in 0..200000 (bus messages stay "
              "under 256 KB)");
  }
  if (service->decode_threads < 1) {
    root.Fail(root.Raw("service"), "service.decode_threads must be >= 1");
  }
  if (service->tiles_per_burst < 1) {
    root.Fail(root.Raw("service"), "service.tiles_per_burst must be >= 1");
  }
  if (service->reply_tile_size <= 0 || service->reply_tile_size > 250) {
    root.Fail(root.Raw("service"), "service.reply_tile_size must be in 1..250");
  }
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

  cairn::mapstore::MapstoreServiceParams params;
  cairn::mapstore::SqliteOptions options;
  options.wal_autocheckpoint_pages = 16384;  // 128 MB of WAL at most between idle checkpoints
  if (!config.empty()) {
    try {
      LoadParams(config, &params, &options);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "cairn-mapstore: %s\n", e.what());
      return 2;
    }
  }
  if (!files_root.empty()) params.files_root = files_root;

  std::error_code ec;
  const auto parent = std::filesystem::path(db).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  auto store = cairn::mapstore::SqliteMapStore::Open(db, options);
  if (!store.ok()) {
    CAIRN_LOG_ERROR("cannot open the map store: %s", store.status().ToString().c_str());
    return 1;
  }

  cairn::runtime::NodeOptions node_options;
  node_options.process_name = "cairn-mapstore";
  try {
    // Maps arrive as bursts of tiles: ask for a large receive buffer unless the URL names one
    // (the kernel caps it at net.core.rmem_max; resend requests cover what a small one drops).
    node_options.lcm_url = cairn::runtime::ResolveLcmUrl(lcm_url);
    if (node_options.lcm_url.rfind("udpm://", 0) == 0 &&
        node_options.lcm_url.find("recv_buf_size=") == std::string::npos) {
      node_options.lcm_url += (node_options.lcm_url.find('?') == std::string::npos ? "?" : "&") +
                              std::string("recv_buf_size=") + std::to_string(recv_buffer_bytes);
    }
    cairn::runtime::Node node(node_options);
    cairn::mapstore::ProfileDeriver deriver = cairn::mapstore::MappingDeriver();
    cairn::mapstore::MapstoreService service(node, **store, deriver, params);
    // Saves do not pay for checkpoints: the WAL is copied into the file when the store is idle.
    cairn::mapstore::SqliteMapStore* sqlite = store->get();
    node.AddTimer(1.0, [sqlite] { sqlite->CheckpointIfIdle(2.0); });
    node.SetState(cairn::runtime::HealthState::kReady);
    node.Event("serving %s (schema %d) on %s", db.c_str(), (*store)->schema_version(),
               node.url().c_str());
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
  } catch (const std::exception& e) {
    CAIRN_LOG_ERROR("%s", e.what());
    return 1;
  }
  return 0;
}
