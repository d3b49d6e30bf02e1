#include "mapstore/mapstore_params.h"

#include <stdexcept>

#include "common/check.h"

namespace cairn::mapstore {

using common::YamlMap;

void MapstoreServiceParams::Validate() const {
  CAIRN_THROW_UNLESS(batch_bytes >= 0 && batch_bytes <= 200000,
                     "service.batch_bytes must be in 0..200000 (bus messages stay under 256 KB)");
  CAIRN_THROW_UNLESS(decode_threads >= 1, "service.decode_threads must be >= 1");
  CAIRN_THROW_UNLESS(max_queued_jobs >= 1, "service.max_queued_jobs must be >= 1");
  resend_limits.Validate();
  CAIRN_THROW_UNLESS(tiles_per_burst >= 1, "service.tiles_per_burst must be >= 1");
  CAIRN_THROW_UNLESS(reply_tile_size > 0 && reply_tile_size <= 250,
                     "service.reply_tile_size must be in 1..250");
  save().Validate();
}

SaveAssemblerParams MapstoreServiceParams::save() const {
  SaveAssemblerParams p;
  p.save_timeout_s = save_timeout_s;
  p.resend_interval_s = resend_interval_s;
  p.staging_timeout_s = staging_timeout_s;
  p.pull_settle_s = pull_settle_s;
  p.max_staged_bytes = max_staged_bytes;
  p.max_pushes = max_pushes;
  return p;
}

SqliteOptions ServiceDatabaseOptions() {
  SqliteOptions options;
  options.wal_autocheckpoint_pages = 16384;
  return options;
}

namespace {

void LoadService(YamlMap s, MapstoreServiceParams* p) {
  s.Get("files_root", &p->files_root);
  s.Get("save_timeout_s", &p->save_timeout_s);
  s.Get("resend_interval_s", &p->resend_interval_s);
  s.Get("staging_timeout_s", &p->staging_timeout_s);
  s.Get("pull_settle_s", &p->pull_settle_s);
  s.Get("reply_cache_size", &p->reply_cache_size);
  s.Get("allow_delete", &p->allow_delete);
  s.Get("max_queued_jobs", &p->max_queued_jobs);
  s.Get("resend_tiles_per_s", &p->resend_limits.rate_per_s);
  s.Get("resend_burst_tiles", &p->resend_limits.burst);
  s.Get("resend_total_tiles_per_s", &p->resend_limits.total_rate_per_s);
  s.Get("resend_total_burst_tiles", &p->resend_limits.total_burst);
  s.Get("max_kept_reply_cells", &p->max_kept_reply_cells);
  s.Get("max_staged_bytes", &p->max_staged_bytes);
  s.Get("max_pushes", &p->max_pushes);
  s.Get("reply_tile_size", &p->reply_tile_size);
  s.Get("max_reply_obstacles", &p->max_reply_obstacles);
  s.Get("tiles_per_burst", &p->tiles_per_burst);
  s.Get("batch_bytes", &p->batch_bytes);
  s.Get("burst_pause_ms", &p->burst_pause_ms);
  s.Get("worker_threads", &p->worker_threads);
  s.Get("decode_threads", &p->decode_threads);
  s.Get("compress_reply_tiles", &p->compress_reply_tiles);
  s.Finish();
}

void LoadDatabase(YamlMap d, SqliteOptions* o) {
  d.Get("busy_timeout_ms", &o->busy_timeout_ms);
  d.Get("write_attempts", &o->write_attempts);
  std::string synchronous;
  if (d.Get("synchronous", &synchronous)) {
    const auto mode = ParseSynchronous(synchronous);
    if (!mode) {
      d.Fail(d.Raw("synchronous"),
             "synchronous must be 'normal' or 'full', not '" + synchronous + "'");
    }
    o->synchronous = *mode;
  }
  d.Get("tile_size_cells", &o->tile_size_cells);
  d.Get("zstd_level", &o->zstd_level);
  d.Get("compression_threads", &o->compression_threads);
  d.Get("cache_size_kib", &o->cache_size_kib);
  d.Get("max_page_count", &o->max_page_count);
  d.Get("wal_autocheckpoint_pages", &o->wal_autocheckpoint_pages);
  d.Finish();
}

}  // namespace

MapstoreParams LoadMapstoreParams(YamlMap& root) {
  MapstoreParams params;
  if (root.Has("service")) LoadService(root.Child("service"), &params.service);
  if (root.Has("database")) LoadDatabase(root.Child("database"), &params.database);
  root.Finish();
  try {
    params.service.Validate();
  } catch (const std::invalid_argument& e) {
    root.Fail(root.Raw("service"), e.what());
  }
  return params;
}

MapstoreParams LoadMapstoreParamsFile(const std::string& path) {
  YamlMap root = YamlMap::LoadFile(path);
  return LoadMapstoreParams(root);
}

}  // namespace cairn::mapstore
