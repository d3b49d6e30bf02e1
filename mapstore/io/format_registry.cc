#include "mapstore/io/format_registry.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <stdexcept>

#include "common/layers.h"
#include "mapstore/map_operations.h"
#include "mapstore/names.h"

namespace cairn::mapstore::io {

using common::Result;
using common::Status;

namespace {

std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace

ExportContext::ExportContext(const MapStore& store, const ProfileDeriver* deriver, MapInfo info,
                             const ExportOptions& options)
    : store_(store), deriver_(deriver), info_(std::move(info)), options_(options) {}

std::string ExportContext::Stem(const std::string& suffix) const {
  if (!options_.stem.empty()) return options_.stem;
  std::string stem = info_.name + "_v" + std::to_string(info_.version);
  if (!suffix.empty()) {
    std::string safe = suffix;
    std::replace(safe.begin(), safe.end(), '/', '_');
    stem += "_" + safe;
  }
  return stem;
}

Result<std::string> ExportContext::ChooseLayer(const std::vector<std::string>& preferred,
                                               bool or_first_layer,
                                               const std::string& why_none) const {
  if (!options_.layer.empty()) return options_.layer;
  if (!options_.profile.empty()) return layers::CostLayer(options_.profile);
  const std::vector<std::string>& have = info_.layers;
  for (const std::string& layer : preferred) {
    if (std::find(have.begin(), have.end(), layer) != have.end()) return layer;
  }
  if (!or_first_layer) return common::InvalidArgumentError(why_none);
  if (have.empty()) return common::NotFoundError("map '" + info_.name + "' has no layers");
  return have.front();
}

Result<common::GridMap> ExportContext::LoadLayer(const std::string& layer) const {
  const Status s = ValidateLayerName(layer);
  if (!s.ok()) return s;
  auto view = LoadForProfile(store_, deriver_, {info_.site, info_.name, info_.version},
                             options_.profile, {{layer}, std::nullopt});
  if (!view.ok()) return view.status();
  return std::move(view->layers);
}

Result<common::ObstacleRegistry> ExportContext::Obstacles() const {
  const MapRef exact{info_.site, info_.name, info_.version};
  if (options_.profile.empty()) return store_.LoadObstacles(exact);
  auto view = LoadForProfile(store_, deriver_, exact, options_.profile,
                             {{layers::CostLayer(options_.profile)}, std::nullopt});
  if (!view.ok()) return view.status();
  return std::move(view->obstacles);
}

Result<OctomapData> ExportContext::Octomap() const {
  return store_.LoadOctomap({info_.site, info_.name, info_.version});
}

ImportTarget::ImportTarget(MapStore& store, const ImportOptions& options,
                           std::optional<MapInfo> latest)
    : store_(store), options_(options), latest_(std::move(latest)) {}

Status ImportTarget::StartFromLatest() {
  if (!latest_) {
    return common::NotFoundError("no map '" + options_.site + "/" + options_.name + "' to import " +
                                 LowerExtension(options_.path) +
                                 " data into (import a grid map first)");
  }
  const MapRef exact{latest_->site, latest_->name, latest_->version};
  auto base = store_.LoadLayers(exact, {});
  if (!base.ok()) return base.status();
  snapshot_.base = std::move(base).value();
  auto obstacles = store_.LoadObstacles(exact);
  if (!obstacles.ok()) return obstacles.status();
  snapshot_.obstacles = std::move(obstacles).value();
  if (latest_->has_octomap) {
    auto octomap = store_.LoadOctomap(exact);
    if (!octomap.ok()) return octomap.status();
    snapshot_.octomap = std::move(octomap).value();
  }
  if (options_.provenance.source_robot.empty()) {
    snapshot_.provenance.source_robot = latest_->provenance.source_robot;
    snapshot_.provenance.source_profile = latest_->provenance.source_profile;
    snapshot_.provenance.source_profile_hash = latest_->provenance.source_profile_hash;
  }
  return Status::Ok();
}

void FormatRegistry::AddExporter(ExportFormat format) {
  if (format.name.empty() || !format.write) {
    throw std::invalid_argument("an export format needs a name and a writer");
  }
  const std::string name = format.name;
  if (!exporters_.emplace(name, std::move(format)).second) {
    throw std::invalid_argument("export format '" + name + "' is registered twice");
  }
}

void FormatRegistry::AddImporter(ImportFormat format) {
  if (format.name.empty() || !format.read) {
    throw std::invalid_argument("an import format needs a name and a reader");
  }
  for (const std::string& ext : format.extensions) {
    if (ext.empty() || ext[0] != '.') {
      throw std::invalid_argument("import format '" + format.name + "': extension '" + ext +
                                  "' must start with a dot");
    }
    for (const auto& [name, other] : importers_) {
      if (std::find(other.extensions.begin(), other.extensions.end(), ext) !=
          other.extensions.end()) {
        throw std::invalid_argument("extension '" + ext + "' is read by '" + name + "' already");
      }
    }
  }
  const std::string name = format.name;
  if (!importers_.emplace(name, std::move(format)).second) {
    throw std::invalid_argument("import format '" + name + "' is registered twice");
  }
}

const ExportFormat* FormatRegistry::FindExporter(const std::string& name) const {
  auto it = exporters_.find(name);
  return it == exporters_.end() ? nullptr : &it->second;
}

const ImportFormat* FormatRegistry::FindImporter(const std::string& name) const {
  auto it = importers_.find(name);
  return it == importers_.end() ? nullptr : &it->second;
}

const ImportFormat* FormatRegistry::ImporterForPath(const std::string& path) const {
  const std::string ext = LowerExtension(path);
  for (const auto& [name, format] : importers_) {
    if (std::find(format.extensions.begin(), format.extensions.end(), ext) !=
        format.extensions.end()) {
      return &format;
    }
  }
  return nullptr;
}

std::vector<std::string> FormatRegistry::ExportNames() const {
  std::vector<std::string> names;
  for (const auto& [name, format] : exporters_) names.push_back(name);
  return names;
}

std::vector<std::string> FormatRegistry::ImportNames() const {
  std::vector<std::string> names;
  for (const auto& [name, format] : importers_) names.push_back(name);
  return names;
}

const FormatRegistry& BuiltinFormats() {
  static const FormatRegistry registry = [] {
    FormatRegistry r;
    RegisterBuiltinFormats(&r);
    return r;
  }();
  return registry;
}

}  // namespace cairn::mapstore::io
