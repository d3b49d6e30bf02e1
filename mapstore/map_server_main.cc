// cairn-map-server: serves a stored map to a robot without a mapper of its own (no lidar), on
// the robot's map channels. Thin: flags, the read-only store, MapServerService, spin.
// `cairn-map serve ...` runs this program with the same flags.

#include <cstdio>
#include <functional>
#include <memory>

#include "common/flags.h"
#include "common/log.h"
#include "mapstore/lcm/map_server_service.h"
#include "mapstore/map_server.h"
#include "mapstore/mapping_deriver.h"
#include "mapstore/sqlite_map_store.h"
#include "services/runtime/node.h"

namespace {

namespace ms = cairn::mapstore;

// Parses the flags into `params`; the parser's exit status, or -1 to go on.
int ParseFlags(int argc, char** argv, ms::MapServerParams* params, std::string* lcm_url) {
  int version = 0;
  cairn::common::FlagParser flags(
      "cairn-map-server",
      "Serves a stored map to a robot that has no mapper of its own (no lidar): loads the map for\n"
      "the robot's profile from the map store (base layers + the profile's derived layers, from\n"
      "the store's cache or derived in memory; the database is only read) and publishes its\n"
      "elevation and cost/<profile> layers as a mapper would, so the robot's cairn-navigator\n"
      "plans on them. With --wait-s it waits for a map that has not been saved yet.\n"
      "Also run as `cairn-map serve`.");
  flags.AddString("db", &params->db_path, "SQLite map store file (opened read-only)");
  flags.AddString("site", &params->ref.site, "site");
  flags.AddString("map", &params->ref.name, "map name");
  flags.AddInt("version", &version, "map version (0 = the latest, and follow newer ones)");
  flags.AddString("profile", &params->profile, "the robot's profile: serves cost/<profile>");
  flags.AddString("robot", &params->robot, "robot id: publishes on <robot>.MAP.*");
  flags.AddDouble("wait-s", &params->wait_s,
                  "wait this long (wall seconds) for the map to be saved (0 = fail at once)");
  flags.AddDouble("poll-s", &params->poll_period_s, "look at the store this often while waiting");
  flags.AddDouble("announce-s", &params->announce_period_s,
                  "manifests of the served layers this often (below the navigator's 0.5 s)");
  flags.AddDouble("follow-s", &params->follow_period_s,
                  "with version 0, look for a newer version this often");
  flags.AddBool("follow", &params->follow_latest,
                "with version 0, serve newer versions as they are saved");
  flags.AddString("lcm-url", lcm_url, "LCM URL (default: LCM_DEFAULT_URL or udpm ttl=0)");
  flags.AddHelpSection(
      "Channels",
      "in:  <robot>.MAP.TILE_RESEND\n"
      "out: <robot>.MAP.TILES, <robot>.MAP.MANIFEST (every --announce-s), <robot>.MAP.OBSTACLES "
      "(the profile's verdicts), HEALTH");
  flags.AddHelpSection("Exit status",
                       "0 stopped by SIGINT/SIGTERM, 1 no map to serve (or it never came), 2 bad "
                       "usage");
  const int rc = flags.Parse(argc, argv);
  params->ref.version = version;
  return rc;
}

// The store, opened read-only on the first attempt that finds the file: the server may start
// before the map store created it.
class LazyStore {
 public:
  explicit LazyStore(std::string path) : path_(std::move(path)) {}
  cairn::common::Result<const ms::MapStore*> operator()() {
    if (!store_) {
      ms::SqliteOptions options;
      options.read_only = true;
      options.create_if_missing = false;
      options.compression_threads = 1;
      auto opened = ms::SqliteMapStore::Open(path_, options);
      if (!opened.ok()) {
        // A missing or half-created file may be fine a moment later.
        return cairn::common::UnavailableError(opened.status().message());
      }
      store_ = std::move(opened).value();
    }
    return store_.get();
  }

 private:
  std::string path_;
  std::unique_ptr<ms::SqliteMapStore> store_;
};

}  // namespace

int main(int argc, char** argv) {
  ms::MapServerParams params;
  params.db_path = "var/cairn.db";
  std::string lcm_url;
  const int rc = ParseFlags(argc, argv, &params, &lcm_url);
  if (rc >= 0) return rc;
  cairn::common::SetLogTag("cairn-map-server");
  try {
    params.Validate();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn-map-server: %s (see --help)\n", e.what());
    return 2;
  }
  try {
    cairn::runtime::NodeOptions node_options;
    node_options.process_name = "cairn-map-server";
    node_options.robot = params.robot;
    node_options.lcm_url = lcm_url;
    cairn::runtime::Node node(node_options);
    const ms::ProfileDeriver deriver = ms::MappingDeriver();
    node.Event("map %s/%s%s for robot %s (profile %s) from %s, bus %s", params.ref.site.c_str(),
               params.ref.name.c_str(),
               params.ref.version > 0 ? (" v" + std::to_string(params.ref.version)).c_str() : "",
               params.robot.c_str(), params.profile.c_str(), params.db_path.c_str(),
               node.url().c_str());
    LazyStore store(params.db_path);
    ms::MapServerService service(node, params, &deriver, std::ref(store));
    node.Spin();
    const bool failed = service.state() == ms::MapServerService::State::kFailed;
    node.SetState(cairn::runtime::HealthState::kStopping);
    if (!failed) node.Event("stopping");
    return failed ? 1 : 0;
  } catch (const std::exception& e) {
    CAIRN_LOG_ERROR("%s", e.what());
    return 1;
  }
}
