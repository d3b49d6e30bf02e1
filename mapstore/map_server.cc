#include "mapstore/map_server.h"

#include <algorithm>
#include <cstdio>

#include "common/check.h"
#include "common/layers.h"
#include "mapstore/map_operations.h"
#include "mapstore/names.h"

namespace cairn::mapstore {

void MapServerParams::Validate() const {
  CAIRN_THROW_UNLESS(!db_path.empty(), "the map server needs a database file");
  const auto check_name = [](const char* what, const std::string& name) {
    const common::Status s = ValidateName(what, name);
    CAIRN_THROW_UNLESS(s.ok(), s.message());
  };
  check_name("site", ref.site);
  check_name("map name", ref.name);
  check_name("profile", profile);
  check_name("robot", robot);
  CAIRN_THROW_UNLESS(ref.version >= 0, "version must be >= 0 (0 = latest), got " << ref.version);
  CAIRN_THROW_UNLESS(wait_s >= 0, "wait_s must be >= 0, got " << wait_s);
  for (double p : {poll_period_s, announce_period_s, registry_period_s, follow_period_s}) {
    CAIRN_THROW_UNLESS(p > 0, "periods must be positive, got " << p);
  }
  CAIRN_THROW_UNLESS(tiles_per_burst >= 1, "tiles_per_burst must be >= 1");
  CAIRN_THROW_UNLESS(burst_pause_ms >= 0, "burst_pause_ms must be >= 0");
}

std::vector<std::string> ServedLayers(const std::string& profile) {
  return {layers::kElevation, layers::kSonarOccupancy, layers::DirectedLayer(profile),
          layers::CostLayer(profile)};
}

bool ServedAsOccupancy(const std::string& layer) { return layer == layers::kSonarOccupancy; }

std::string ServedMapName(const MapRef& ref) { return ref.site + "/" + ref.name; }

common::Result<ServedMap> LoadServedMap(const MapStore& store, const ProfileDeriver* deriver,
                                        const MapRef& ref, const std::string& profile) {
  // Pin the version first, so that the layers and the obstacles come from the same one even
  // when a newer version is saved meanwhile.
  auto info = store.GetMapInfo(ref);
  if (!info.ok()) return info.status();
  const MapRef exact{info->site, info->name, info->version};
  const std::string cost = layers::CostLayer(profile);
  std::vector<std::string> wanted;
  const auto& base = info->layers;
  for (const char* name : {layers::kElevation, layers::kSonarOccupancy}) {
    if (std::find(base.begin(), base.end(), name) != base.end()) wanted.push_back(name);
  }
  wanted.push_back(layers::DirectedLayer(profile));
  wanted.push_back(cost);
  auto view = LoadForProfile(store, deriver, exact, profile, {wanted, std::nullopt});
  if (!view.ok()) return view.status();
  if (!view->layers.HasLayer(cost)) {
    return common::NotFoundError("the derivation for profile '" + profile + "' gave no layer '" +
                                 cost + "'");
  }
  ServedMap served;
  served.info = std::move(view->info);
  served.profile = profile;
  served.layers = std::move(view->layers);
  served.obstacles = std::move(view->obstacles);
  served.obstacles.map_version = served.info.version;
  served.from_cache = view->from_cache;
  served.derive_ms = view->derive_ms;
  return served;
}

bool MayAppearLater(const common::Status& status) {
  return status.code() == common::StatusCode::kNotFound ||
         status.code() == common::StatusCode::kUnavailable;
}

MapWaiter::MapWaiter(double wait_s) : wait_s_(wait_s) {
  CAIRN_THROW_UNLESS(wait_s >= 0, "wait_s must be >= 0, got " << wait_s);
}

MapWaiter::Decision MapWaiter::OnAttempt(double elapsed_s, const common::Status& status) {
  char buf[64];
  Decision d;
  if (status.ok()) {
    d.action = Action::kServe;
    if (waiting_since_s_) {
      std::snprintf(buf, sizeof(buf), "%.1f", elapsed_s);
      d.log = std::string("the map is there after waiting ") + buf + " s";
    }
    return d;
  }
  if (!MayAppearLater(status) || elapsed_s >= wait_s_) {
    d.action = Action::kGiveUp;
    if (!MayAppearLater(status)) {
      d.log = "cannot serve the map: " + status.ToString();
    } else {
      std::snprintf(buf, sizeof(buf), "%.1f", wait_s_);
      d.log = (wait_s_ > 0 ? std::string("gave up after waiting ") + buf + " s: "
                           : std::string("no map to serve: ")) +
              status.ToString();
    }
    return d;
  }
  d.action = Action::kWait;
  if (!waiting_since_s_) {
    waiting_since_s_ = elapsed_s;
    std::snprintf(buf, sizeof(buf), "%.1f", wait_s_);
    d.log = std::string("waiting up to ") + buf + " s for the map (" + status.message() + ")";
  }
  return d;
}

}  // namespace cairn::mapstore
