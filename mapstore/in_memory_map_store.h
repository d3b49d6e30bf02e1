#pragma once

#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "mapstore/map_store.h"

/// @file
/// InMemoryMapStore: the MapStore twin for unit tests. Same behaviour as SqliteMapStore
/// (versions, soft delete, derived cache, profiles, places, audit), nothing on disk.
/// Thread-safe (one mutex).

namespace cairn::mapstore {

class InMemoryMapStore final : public MapStore {
 public:
  /// @param tile_size_cells reported in MapInfo, as SqliteMapStore would.
  explicit InMemoryMapStore(int tile_size_cells = 100) : tile_size_(tile_size_cells) {}

  common::Result<MapInfo> SaveMap(const MapSnapshot& snapshot, const WriteContext& ctx) override;
  common::Result<MapInfo> GetMapInfo(const MapRef& ref) const override;
  common::Result<std::vector<MapInfo>> ListMaps(const MapFilter& filter) const override;
  common::Result<common::GridMap> LoadLayers(const MapRef& ref,
                                             const LayerQuery& query) const override;
  common::Result<common::ObstacleRegistry> LoadObstacles(const MapRef& ref) const override;
  common::Result<OctomapData> LoadOctomap(const MapRef& ref) const override;
  common::Status DeleteMap(const MapRef& ref, const WriteContext& ctx) override;
  common::Status PutProfile(const common::RobotProfile& profile, const WriteContext& ctx) override;
  common::Result<StoredProfile> GetProfile(const std::string& name) const override;
  common::Result<std::vector<StoredProfile>> ListProfiles() const override;
  common::Result<std::optional<DerivedProfile>> FindDerived(const MapRef& ref,
                                                            const std::string& profile_hash,
                                                            const std::string& code_version,
                                                            const LayerQuery& query) const override;
  common::Result<std::vector<DerivedInfo>> ListDerived(const MapRef& ref) const override;
  common::Status PutDerived(const MapRef& ref, const DerivedProfile& derived,
                            const WriteContext& ctx) override;
  common::Status PutPlaces(const std::string& site, const std::vector<Place>& places,
                           const WriteContext& ctx) override;
  common::Result<std::vector<Place>> ListPlaces(const std::string& site) const override;
  common::Result<std::vector<std::string>> ListSites() const override;
  common::Result<std::vector<AuditEntry>> ListAudit(int limit) const override;
  common::Result<std::optional<AuditEntry>> FindRequest(const std::string& actor,
                                                        int64_t request_id) const override;
  /// Always ok: nothing in memory can rot.
  common::Result<CheckReport> Check(const ProgressFn& progress = nullptr) const override;

 private:
  struct Version {
    MapInfo info;
    common::GridMap base;
    common::ObstacleRegistry obstacles;
    std::optional<OctomapData> octomap;
    std::map<std::pair<std::string, std::string>, DerivedProfile> derived;
  };
  struct Site {
    std::map<std::string, std::vector<Version>> maps;  // versions in order, version = index + 1
    std::map<std::string, Place> places;
  };
  common::Result<const Version*> Resolve(const MapRef& ref) const;
  void Audit(const WriteContext& ctx, const std::string& op, const std::string& site,
             const std::string& map, int64_t version, const std::string& detail);

  int tile_size_;
  mutable std::mutex mutex_;
  std::map<std::string, Site> sites_;
  std::map<std::string, std::vector<StoredProfile>> profiles_;  // history, newest last
  std::vector<AuditEntry> audit_;
};

}  // namespace cairn::mapstore
