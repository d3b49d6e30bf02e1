#include "mapstore/in_memory_map_store.h"

#include <algorithm>

#include "mapstore/blob_codec.h"
#include "mapstore/names.h"
#include "mapstore/store_util.h"

namespace cairn::mapstore {

using common::Result;
using common::Status;

namespace {

// The cells of `box` of every wanted layer, as SqliteMapStore returns them.
Result<common::GridMap> Crop(const common::GridMap& full, const std::vector<std::string>& wanted,
                             const std::optional<CellBox>& region) {
  const common::GridGeometry& g = full.geometry();
  const CellBox box = region ? ClipBox(*region, g) : CellBox{0, 0, g.size_x, g.size_y};
  if (box.empty()) return common::InvalidArgumentError("the region does not overlap the map");
  common::GridMap out(SubGeometry(g, box));
  for (const std::string& name : wanted) {
    out.AddLayer(name) = full.at(name).block(box.min_ix, box.min_iy, box.max_ix - box.min_ix,
                                             box.max_iy - box.min_iy);
  }
  return out;
}

// Stored order: obstacles by id, verdicts by profile (as the SQLite store reads them back).
common::ObstacleRegistry Canonical(common::ObstacleRegistry registry, int64_t version) {
  registry.map_version = version;
  std::sort(registry.obstacles.begin(), registry.obstacles.end(),
            [](const common::Obstacle& a, const common::Obstacle& b) { return a.id < b.id; });
  for (auto& o : registry.obstacles) {
    std::sort(o.verdicts.begin(), o.verdicts.end(),
              [](const common::ObstacleVerdict& a, const common::ObstacleVerdict& b) {
                return a.profile < b.profile;
              });
  }
  return registry;
}

}  // namespace

void InMemoryMapStore::Audit(const WriteContext& ctx, const std::string& op,
                             const std::string& site, const std::string& map, int64_t version,
                             const std::string& detail) {
  AuditEntry e;
  e.id = static_cast<int64_t>(audit_.size()) + 1;
  e.utime = ctx.utime != 0 ? ctx.utime : WallUtime();
  e.actor = ctx.actor.empty() ? "unknown" : ctx.actor;
  e.op = op;
  e.site = site;
  e.map = map;
  e.version = version;
  e.request_id = ctx.request_id;
  e.detail = detail;
  audit_.push_back(std::move(e));
}

Result<const InMemoryMapStore::Version*> InMemoryMapStore::Resolve(const MapRef& ref) const {
  Status s = ValidateName("site name", ref.site);
  if (!s.ok()) return s;
  if (!(s = ValidateName("map name", ref.name)).ok()) return s;
  if (ref.version < 0) return common::InvalidArgumentError("map version must be >= 0 (0 = latest)");
  auto site = sites_.find(ref.site);
  const std::vector<Version>* versions = nullptr;
  if (site != sites_.end()) {
    auto it = site->second.maps.find(ref.name);
    if (it != site->second.maps.end()) versions = &it->second;
  }
  if (versions == nullptr || versions->empty()) {
    return common::NotFoundError("no map '" + ref.name + "' in site '" + ref.site + "'");
  }
  const std::string label = "map '" + ref.site + "/" + ref.name + "'";
  if (ref.version == 0) {
    for (auto it = versions->rbegin(); it != versions->rend(); ++it) {
      if (!it->info.deleted) return &*it;
    }
    return common::NotFoundError(label + " is deleted");
  }
  if (ref.version > static_cast<int64_t>(versions->size())) {
    return common::NotFoundError(label + " has no version " + std::to_string(ref.version));
  }
  const Version& v = (*versions)[ref.version - 1];
  if (v.info.deleted) {
    return common::NotFoundError(label + " version " + std::to_string(ref.version) + " is deleted");
  }
  return &v;
}

Result<MapInfo> InMemoryMapStore::SaveMap(const MapSnapshot& snapshot, const WriteContext& ctx) {
  Status s = ValidateSnapshot(snapshot);
  if (!s.ok()) return s;
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<Version>& versions = sites_[snapshot.site].maps[snapshot.name];
  Version v;
  v.info.site = snapshot.site;
  v.info.name = snapshot.name;
  v.info.version = static_cast<int64_t>(versions.size()) + 1;
  v.info.provenance = snapshot.provenance;
  if (v.info.provenance.created_utime == 0) v.info.provenance.created_utime = WallUtime();
  v.info.geometry = snapshot.base.geometry();
  v.info.tile_size = tile_size_;
  v.info.layers = snapshot.base.layer_names();
  std::sort(v.info.layers.begin(), v.info.layers.end());
  v.info.num_obstacles = static_cast<int>(snapshot.obstacles.obstacles.size());
  v.info.has_octomap = snapshot.octomap.has_value();
  v.base = snapshot.base;
  v.obstacles = Canonical(snapshot.obstacles, v.info.version);
  v.octomap = snapshot.octomap;
  const MapInfo info = v.info;
  versions.push_back(std::move(v));
  Audit(ctx, "save", snapshot.site, snapshot.name, info.version,
        std::to_string(info.layers.size()) + " layers");
  return info;
}

Result<MapInfo> InMemoryMapStore::GetMapInfo(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto v = Resolve(ref);
  if (!v.ok()) return v.status();
  return (*v)->info;
}

Result<std::vector<MapInfo>> InMemoryMapStore::ListMaps(const MapFilter& filter) const {
  Status s;
  if (!filter.site.empty() && !(s = ValidateName("site name", filter.site)).ok()) return s;
  if (!filter.name.empty() && !(s = ValidateName("map name", filter.name)).ok()) return s;
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<MapInfo> out;
  for (const auto& [site_name, site] : sites_) {
    if (!filter.site.empty() && site_name != filter.site) continue;
    for (const auto& [map_name, versions] : site.maps) {
      if (!filter.name.empty() && map_name != filter.name) continue;
      std::vector<const Version*> eligible;
      for (const Version& v : versions) {
        if (!v.info.deleted || filter.include_deleted) eligible.push_back(&v);
      }
      if (eligible.empty()) continue;
      if (filter.all_versions) {
        for (const Version* v : eligible) out.push_back(v->info);
      } else {
        out.push_back(eligible.back()->info);
      }
    }
  }
  return out;
}

Result<common::GridMap> InMemoryMapStore::LoadLayers(const MapRef& ref,
                                                     const LayerQuery& query) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto v = Resolve(ref);
  if (!v.ok()) return v.status();
  std::vector<std::string> wanted = query.layers;
  if (wanted.empty()) wanted = (*v)->info.layers;
  std::map<std::string, int64_t> known;
  for (const auto& name : (*v)->info.layers) known[name] = 0;
  for (const std::string& name : wanted) {
    if (!known.count(name)) {
      return common::NotFoundError(LayerNotFoundMessage(ref, (*v)->info.version, name, known));
    }
  }
  return Crop((*v)->base, wanted, query.region);
}

Result<common::ObstacleRegistry> InMemoryMapStore::LoadObstacles(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto v = Resolve(ref);
  if (!v.ok()) return v.status();
  return (*v)->obstacles;
}

Result<OctomapData> InMemoryMapStore::LoadOctomap(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto v = Resolve(ref);
  if (!v.ok()) return v.status();
  if (!(*v)->octomap) {
    return common::NotFoundError("map '" + ref.site + "/" + ref.name + "' version " +
                                 std::to_string((*v)->info.version) + " has no OctoMap");
  }
  return *(*v)->octomap;
}

Status InMemoryMapStore::DeleteMap(const MapRef& ref, const WriteContext& ctx) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto v = Resolve(ref);
  if (!v.ok()) return v.status();
  std::vector<Version>& versions = sites_[ref.site].maps[ref.name];
  int changed = 0;
  for (Version& version : versions) {
    if (version.info.deleted) continue;
    if (ref.version == 0 || version.info.version == ref.version) {
      version.info.deleted = true;
      ++changed;
    }
  }
  Audit(ctx, "delete", ref.site, ref.name, ref.version,
        ref.version == 0 ? std::to_string(changed) + " versions" : "one version");
  return Status::Ok();
}

Status InMemoryMapStore::PutProfile(const common::RobotProfile& profile, const WriteContext& ctx) {
  Status s = ValidateProfile(profile);
  if (!s.ok()) return s;
  std::lock_guard<std::mutex> lock(mutex_);
  auto& history = profiles_[profile.name];
  const std::string hash = profile.ContentHash();
  if (!history.empty() && history.back().content_hash == hash) return Status::Ok();
  StoredProfile stored;
  stored.profile = common::LoadRobotProfileString(profile.ToYaml());  // canonical form
  stored.content_hash = hash;
  stored.updated_utime = WallUtime();
  history.erase(std::remove_if(history.begin(), history.end(),
                               [&](const StoredProfile& p) { return p.content_hash == hash; }),
                history.end());
  history.push_back(std::move(stored));
  Audit(ctx, "put_profile", "", "", 0, profile.name + " " + hash);
  return Status::Ok();
}

Result<StoredProfile> InMemoryMapStore::GetProfile(const std::string& name) const {
  Status s = ValidateName("profile name", name);
  if (!s.ok()) return s;
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = profiles_.find(name);
  if (it == profiles_.end() || it->second.empty()) {
    std::vector<std::string> known;
    for (const auto& [k, v] : profiles_) known.push_back(k);
    return common::NotFoundError(ProfileNotFoundMessage(name, known));
  }
  return it->second.back();
}

Result<std::vector<StoredProfile>> InMemoryMapStore::ListProfiles() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<StoredProfile> out;
  for (const auto& [name, history] : profiles_) {
    if (!history.empty()) out.push_back(history.back());
  }
  return out;
}

Result<std::optional<DerivedProfile>> InMemoryMapStore::FindDerived(const MapRef& ref,
                                                                    const std::string& profile_hash,
                                                                    const std::string& code_version,
                                                                    const LayerQuery& query) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto v = Resolve(ref);
  if (!v.ok()) return v.status();
  auto it = (*v)->derived.find({profile_hash, code_version});
  if (it == (*v)->derived.end()) return std::optional<DerivedProfile>();
  DerivedProfile out = it->second;
  std::vector<std::string> wanted = query.layers;
  if (wanted.empty()) wanted = out.layers.layer_names();
  for (const std::string& name : wanted) {
    if (!out.layers.HasLayer(name)) {
      return common::NotFoundError("the cached layers of profile '" + out.profile_name +
                                   "' have no layer '" + name + "'");
    }
  }
  auto cropped = Crop(it->second.layers, wanted, query.region);
  if (!cropped.ok()) return cropped.status();
  out.layers = std::move(cropped).value();
  return std::optional<DerivedProfile>(std::move(out));
}

Result<std::vector<DerivedInfo>> InMemoryMapStore::ListDerived(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto v = Resolve(ref);
  if (!v.ok()) return v.status();
  std::vector<DerivedInfo> out;
  for (const auto& [key, d] : (*v)->derived) {
    DerivedInfo info;
    info.profile_name = d.profile_name;
    info.profile_hash = d.profile_hash;
    info.code_version = d.code_version;
    info.created_utime = d.created_utime;
    info.layers = d.layers.layer_names();
    out.push_back(std::move(info));
  }
  std::stable_sort(out.begin(), out.end(), [](const DerivedInfo& a, const DerivedInfo& b) {
    return a.profile_name < b.profile_name;
  });
  return out;
}

Status InMemoryMapStore::PutDerived(const MapRef& ref, const DerivedProfile& derived,
                                    const WriteContext& ctx) {
  Status s = ValidateDerived(derived);
  if (!s.ok()) return s;
  std::lock_guard<std::mutex> lock(mutex_);
  auto v = Resolve(ref);
  if (!v.ok()) return v.status();
  if (derived.layers.geometry() != (*v)->info.geometry) {
    return common::InvalidArgumentError("derived layers do not have the geometry of map '" +
                                        ref.site + "/" + ref.name + "'");
  }
  Version* version = const_cast<Version*>(*v);
  const auto key = std::make_pair(derived.profile_hash, derived.code_version);
  if (version->derived.count(key)) return Status::Ok();
  DerivedProfile stored = derived;
  if (stored.created_utime == 0) stored.created_utime = WallUtime();
  version->derived.emplace(key, std::move(stored));
  Audit(ctx, "derive", ref.site, ref.name, version->info.version,
        "profile " + derived.profile_name + " (" + derived.profile_hash + "), code " +
            derived.code_version);
  return Status::Ok();
}

Status InMemoryMapStore::PutPlaces(const std::string& site, const std::vector<Place>& places,
                                   const WriteContext& ctx) {
  Status s = ValidatePlaces(site, places);
  if (!s.ok()) return s;
  std::lock_guard<std::mutex> lock(mutex_);
  std::string names;
  for (const Place& p : places) {
    sites_[site].places[p.name] = p;
    names += (names.empty() ? "" : ", ") + p.name;
  }
  if (places.empty()) sites_[site];
  Audit(ctx, "put_place", site, "", 0, names);
  return Status::Ok();
}

Result<std::vector<Place>> InMemoryMapStore::ListPlaces(const std::string& site) const {
  Status s = ValidateName("site name", site);
  if (!s.ok()) return s;
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = sites_.find(site);
  if (it == sites_.end()) return common::NotFoundError("no site '" + site + "'");
  std::vector<Place> out;
  for (const auto& [name, place] : it->second.places) out.push_back(place);
  return out;
}

Result<std::vector<std::string>> InMemoryMapStore::ListSites() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::string> out;
  for (const auto& [name, site] : sites_) out.push_back(name);
  return out;
}

Result<std::vector<AuditEntry>> InMemoryMapStore::ListAudit(int limit) const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<AuditEntry> out;
  for (auto it = audit_.rbegin(); it != audit_.rend() && static_cast<int>(out.size()) < limit;
       ++it) {
    out.push_back(*it);
  }
  return out;
}

Result<std::optional<AuditEntry>> InMemoryMapStore::FindRequest(const std::string& actor,
                                                                int64_t request_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto it = audit_.rbegin(); it != audit_.rend(); ++it) {
    if (it->actor == actor && it->request_id == request_id) {
      return std::optional<AuditEntry>(*it);
    }
  }
  return std::optional<AuditEntry>();
}

Result<CheckReport> InMemoryMapStore::Check(const ProgressFn& progress) const {
  std::lock_guard<std::mutex> lock(mutex_);
  CheckReport report;
  for (const auto& [name, site] : sites_) {
    for (const auto& [map, versions] : site.maps) {
      report.maps_checked += static_cast<int64_t>(versions.size());
    }
  }
  if (progress) progress(1.0, "done");
  return report;
}

}  // namespace cairn::mapstore
