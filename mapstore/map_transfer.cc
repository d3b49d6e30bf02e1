#include "mapstore/map_transfer.h"

#include <algorithm>
#include <filesystem>

#include "common/layers.h"
#include "mapstore/map_operations.h"
#include "mapstore/names.h"

namespace cairn::mapstore {

namespace fs = std::filesystem;
using common::Result;
using common::Status;

namespace {

std::string LowerExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

std::string FileSafe(const std::string& layer) {
  std::string out = layer;
  std::replace(out.begin(), out.end(), '/', '_');
  return out;
}

}  // namespace

Result<std::string> DefaultExportLayer(const MapInfo& info, const std::string& format,
                                       const std::string& profile) {
  if (!profile.empty()) return layers::CostLayer(profile);
  const auto has = [&](const std::string& l) {
    return std::find(info.layers.begin(), info.layers.end(), l) != info.layers.end();
  };
  if (format == "ros") {
    for (const char* l : {layers::kFinal, layers::kStaticMap, layers::kOccupancy,
                          layers::kOccupancyLogOdds, layers::kLongTerm, layers::kShortTerm}) {
      if (has(l)) return std::string(l);
    }
    return common::InvalidArgumentError(
        "map '" + info.name +
        "' has no occupancy layer to export as a ROS map; name a --layer "
        "or a --profile (its cost layer)");
  }
  if (has(layers::kElevation)) return std::string(layers::kElevation);
  if (info.layers.empty()) return common::NotFoundError("map '" + info.name + "' has no layers");
  return info.layers.front();
}

Result<std::vector<std::string>> ExportMap(const MapStore& store, const ProfileDeriver* deriver,
                                           const ExportOptions& options) {
  auto info = store.GetMapInfo(options.ref);
  if (!info.ok()) return info.status();
  const MapRef exact{info->site, info->name, info->version};
  std::string stem =
      options.stem.empty() ? info->name + "_v" + std::to_string(info->version) : options.stem;
  const std::string& format = options.format;
  if (format == "ros" || format == "png") {
    std::string layer = options.layer;
    if (layer.empty()) {
      auto chosen = DefaultExportLayer(*info, format, options.profile);
      if (!chosen.ok()) return chosen.status();
      layer = *chosen;
    }
    Status s = ValidateLayerName(layer);
    if (!s.ok()) return s;
    auto view = LoadForProfile(store, deriver, exact, options.profile, {{layer}, std::nullopt});
    if (!view.ok()) return view.status();
    if (options.stem.empty()) stem += "_" + FileSafe(layer);
    if (format == "png") {
      auto path = io::WritePng(options.folder, stem, view->layers, layer);
      if (!path.ok()) return path.status();
      return std::vector<std::string>{*path};
    }
    auto occupancy = io::OccupancyPercent(view->layers, layer);
    if (!occupancy.ok()) return occupancy.status();
    return io::WriteRosMap(options.folder, stem, view->layers.geometry(), *occupancy, options.ros);
  }
  if (format == "bt" || format == "ot") {
    auto octomap = store.LoadOctomap(exact);
    if (!octomap.ok()) return octomap.status();
    auto path = io::WriteOctomap(options.folder, stem, *octomap, format == "bt");
    if (!path.ok()) return path.status();
    return std::vector<std::string>{*path};
  }
  if (format == "csv") {
    common::ObstacleRegistry registry;
    if (options.profile.empty()) {
      auto stored = store.LoadObstacles(exact);
      if (!stored.ok()) return stored.status();
      registry = std::move(stored).value();
    } else {
      auto view = LoadForProfile(store, deriver, exact, options.profile,
                                 {{layers::CostLayer(options.profile)}, std::nullopt});
      if (!view.ok()) return view.status();
      registry = std::move(view->obstacles);
    }
    auto path = io::WriteObstaclesCsv(options.folder, stem + "_obstacles", registry);
    if (!path.ok()) return path.status();
    return std::vector<std::string>{*path};
  }
  return common::InvalidArgumentError("unknown export format '" + format +
                                      "' (ros, png, bt, ot, csv)");
}

Result<MapInfo> ImportMap(MapStore& store, const ImportOptions& options, const WriteContext& ctx) {
  Status s = ValidateName("site name", options.site);
  if (!s.ok()) return s;
  if (!(s = ValidateName("map name", options.name)).ok()) return s;
  const std::string ext = LowerExtension(options.path);
  MapSnapshot snapshot;
  snapshot.site = options.site;
  snapshot.name = options.name;
  snapshot.provenance = options.provenance;
  if (snapshot.provenance.code_version.empty()) {
    snapshot.provenance.code_version = "import " + fs::path(options.path).filename().string();
  }

  // The latest version, if any, is where the new one starts.
  auto latest = store.GetMapInfo({options.site, options.name, 0});
  if (!latest.ok() && latest.status().code() != common::StatusCode::kNotFound) {
    return latest.status();
  }
  auto start_from_latest = [&]() -> Status {
    const MapRef exact{latest->site, latest->name, latest->version};
    auto base = store.LoadLayers(exact, {});
    if (!base.ok()) return base.status();
    snapshot.base = std::move(base).value();
    auto obstacles = store.LoadObstacles(exact);
    if (!obstacles.ok()) return obstacles.status();
    snapshot.obstacles = std::move(obstacles).value();
    if (latest->has_octomap) {
      auto octomap = store.LoadOctomap(exact);
      if (!octomap.ok()) return octomap.status();
      snapshot.octomap = std::move(octomap).value();
    }
    if (options.provenance.source_robot.empty()) {
      snapshot.provenance.source_robot = latest->provenance.source_robot;
      snapshot.provenance.source_profile = latest->provenance.source_profile;
      snapshot.provenance.source_profile_hash = latest->provenance.source_profile_hash;
    }
    return Status::Ok();
  };

  if (ext == ".yaml" || ext == ".yml") {
    if (!(s = ValidateLayerName(options.layer)).ok()) return s;
    auto ros = io::ReadRosMap(options.path);
    if (!ros.ok()) return ros.status();
    if (latest.ok() && latest->geometry == ros->geometry) {
      if (!(s = start_from_latest()).ok()) return s;
    } else {
      snapshot.base = common::GridMap(ros->geometry);
    }
    snapshot.base.AddLayer(options.layer) = ros->occupancy;
    if (snapshot.provenance.parameters.empty()) {
      snapshot.provenance.parameters =
          std::string("mode: ") + io::PgmModeName(ros->options.mode) +
          "\noccupied_thresh: " + std::to_string(ros->options.occupied_thresh) +
          "\nfree_thresh: " + std::to_string(ros->options.free_thresh) + "\n";
    }
  } else if (ext == ".bt" || ext == ".ot" || ext == ".csv") {
    if (!latest.ok()) {
      return common::NotFoundError("no map '" + options.site + "/" + options.name + "' to import " +
                                   ext + " data into (import a grid map first)");
    }
    if (!(s = start_from_latest()).ok()) return s;
    if (ext == ".csv") {
      auto registry = io::ReadObstaclesCsv(options.path);
      if (!registry.ok()) return registry.status();
      snapshot.obstacles = std::move(registry).value();
    } else {
      auto octomap = io::ReadOctomap(options.path);
      if (!octomap.ok()) return octomap.status();
      snapshot.octomap = std::move(octomap).value();
    }
  } else {
    return common::InvalidArgumentError("cannot import '" + options.path +
                                        "': expected a .yaml map, an OctoMap .bt/.ot or an "
                                        "obstacle .csv");
  }
  return store.SaveMap(snapshot, ctx);
}

}  // namespace cairn::mapstore
