#include "services/mapping/mapper_config.h"

#include <cctype>
#include <filesystem>
#include <sstream>

#include "common/check.h"
#include "common/yaml_reader.h"
#include "services/mapping/mapper_layers.h"

namespace cairn::mapping {

void MapperParams::Validate() const {
  CAIRN_THROW_UNLESS(!robot.empty(), "the mapper needs a robot name");
  CAIRN_THROW_UNLESS(!map_name.empty(), "map_name must not be empty");
  inputs.Validate();
  CAIRN_THROW_UNLESS(max_pending_revolutions >= 1, "max_pending_revolutions must be >= 1");
  CAIRN_THROW_UNLESS(tiles_per_burst >= 1, "tiles_per_burst must be >= 1");
  CAIRN_THROW_UNLESS(burst_pause_ms >= 0, "burst_pause_ms must be >= 0");
  CAIRN_THROW_UNLESS(max_queued_jobs >= 1, "max_queued_jobs must be >= 1");
  resend_limits.Validate();
  if (!long_term_store.empty()) {
    const auto slash = long_term_store.find('/');
    CAIRN_THROW_UNLESS(slash != std::string::npos && slash > 0 &&
                           slash + 1 < long_term_store.size() &&
                           long_term_store.find('/', slash + 1) == std::string::npos,
                       "long_term_store must be SITE/MAP, got '" << long_term_store << "'");
    CAIRN_THROW_UNLESS(core.Has(kDynamicLayerName),
                       "long_term_store needs the dynamic layers (a static map)");
    CAIRN_THROW_UNLESS(long_term_save_period_s > 0, "long_term_save_period_s must be positive");
  }
  core.Validate();
}

MapperConfig LoadMapperConfig(common::YamlMap& m) {
  MapperConfig config;
  MapperParams& p = config.params;
  m.Get("map_name", &p.map_name);
  if (m.Has("pose_source")) {
    const YAML::Node node = m.Raw("pose_source");
    try {
      p.inputs.pose_source = PoseSourceFromName(node.as<std::string>());
    } catch (const std::exception&) {
      m.Fail(node, "pose_source must be 'ground_truth' or 'odometry'");
    }
  }
  m.Get("max_pose_gap_s", &p.inputs.max_pose_gap_s);
  m.Get("imu_attitude", &p.inputs.imu_attitude);
  m.Get("max_imu_gap_s", &p.inputs.max_imu_gap_s);
  if (m.Has("lidar_mount")) {
    common::YamlMap mount = m.Child("lidar_mount");
    p.inputs.lidar_mount = LoadMountPose(mount);
  }
  if (m.Has("profiles")) {
    const YAML::Node node = m.Raw("profiles");
    try {
      config.profiles = node.as<std::vector<std::string>>();
    } catch (const YAML::Exception&) {
      m.Fail(node, "profiles must be a list of names");
    }
  }
  // The layers' publish periods, at the top level as they always were.
  m.Get("publish_period_s", &p.core.terrain.publish_period_s);
  m.Get("slow_publish_period_s", &p.core.terrain.slow_publish_period_s);
  m.Get("registry_period_s", &p.core.terrain.registry_period_s);
  m.Get("max_announce_without_data_s", &p.core.terrain.max_announce_without_data_s);
  double occupancy_period_s = p.core.occupancy.publish_period_s;
  m.Get("occupancy_period_s", &occupancy_period_s);
  p.core.occupancy.publish_period_s = p.core.dynamic.publish_period_s = occupancy_period_s;
  m.Get("max_pending_revolutions", &p.max_pending_revolutions);
  m.Get("tiles_per_burst", &p.tiles_per_burst);
  m.Get("burst_pause_ms", &p.burst_pause_ms);
  m.Get("snapshot_dir", &p.snapshot_dir);
  m.Get("allow_reset", &p.allow_reset);
  m.Get("allow_snapshot", &p.allow_snapshot);
  m.Get("max_queued_jobs", &p.max_queued_jobs);
  m.Get("resend_tiles_per_s", &p.resend_limits.rate_per_s);
  m.Get("resend_burst_tiles", &p.resend_limits.burst);
  m.Get("resend_total_tiles_per_s", &p.resend_limits.total_rate_per_s);
  m.Get("resend_total_burst_tiles", &p.resend_limits.total_burst);
  for (const std::string& layer : RegisteredLayers()) {
    if (!m.Has(layer)) continue;
    common::YamlMap section = m.Child(layer);
    if (layer == kDynamicLayerName) {
      // The store that remembers the long-term layer is the process's business.
      section.Get("long_term_store", &p.long_term_store);
      section.Get("long_term_save_period_s", &p.long_term_save_period_s);
      section.Get("long_term_load_timeout_s", &p.long_term_load_timeout_s);
    }
    LoadMapperLayerSection(layer, section, &p.core);
  }
  m.Finish();
  return config;
}

MapperConfig LoadMapperConfigFile(const std::string& path) {
  common::YamlMap root = common::YamlMap::LoadFile(path);
  return LoadMapperConfig(root);
}

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
    if (b != std::string::npos) out.push_back(item.substr(b, e - b + 1));
  }
  return out;
}

common::Result<common::RobotProfile> ResolveProfileByName(const std::string& dir,
                                                          const std::string& name) {
  if (name.empty() || name.size() > 64) {
    return common::InvalidArgumentError("a profile name has 1 to 64 characters");
  }
  for (char c : name) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) {
      return common::InvalidArgumentError(
          "bad profile name (letters, digits, '_' and '-' only; profiles are taken from the "
          "profiles folder by name)");
    }
  }
  return ResolveProfile(dir, name);
}

common::Result<common::RobotProfile> ResolveProfile(const std::string& dir,
                                                    const std::string& name) {
  const bool is_path = name.find('/') != std::string::npos ||
                       (name.size() > 5 && name.substr(name.size() - 5) == ".yaml");
  if (!is_path) {
    for (char c : name) {
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) {
        return common::InvalidArgumentError("bad profile name '" + name + "'");
      }
    }
  }
  const std::string path = is_path ? name : dir + "/" + name + ".yaml";
  if (!std::filesystem::exists(path)) {
    return common::NotFoundError("no profile '" + name + "' (looked for " + path + ")");
  }
  try {
    return common::LoadRobotProfileFile(path);
  } catch (const std::exception& e) {
    return common::InvalidArgumentError(e.what());
  }
}

}  // namespace cairn::mapping
