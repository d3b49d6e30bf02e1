#pragma once

#include <string>
#include <vector>

#include "services/mapping/mapper_layer.h"
#include "services/mapping/octomap_layer.h"

/// @file
/// The OctoMap as a mapper layer ("octomap"): every every_revolutions-th lidar revolution into
/// an OctomapLayer, on a thread of its own in a live mapper (a revolution costs far more here
/// than in the other layers). Published as the tree's .bt stream in chunks, written as
/// octomap.bt.

namespace cairn::mapping {

struct OctomapMapperLayerParams {
  OctomapLayerParams tree;
  int every_revolutions{10};
  double publish_period_s{5.0};

  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

/// Reads an `octomap` section (the tree keys, every_revolutions, publish_period_s) and finishes
/// it: the caller reads `enabled` first. @throws common::ConfigError naming the file and line
/// of a bad or unknown key.
OctomapMapperLayerParams LoadOctomapMapperLayerParams(common::YamlMap& map);

class OctomapMapperLayer : public MapperLayer {
 public:
  /// @throws std::invalid_argument if the params are invalid.
  explicit OctomapMapperLayer(const OctomapMapperLayerParams& params);

  const std::string& name() const override;
  uint32_t inputs() const override { return kLidarRevolutions; }
  LayerSchedule schedule() const override;
  std::vector<std::string> OwnedLayers() const override { return {"octomap"}; }
  void OnRevolution(const RevolutionInput& input, RevolutionReport* report) override;
  void Reset() override { tree_ = OctomapLayer(params_.tree); }
  int64_t version() const override { return tree_.version(); }
  /// octomap.bt, and `octomap: octomap.bt` in map.yaml.
  common::Status WriteOutputs(const std::string& dir, std::ostream& yaml) const override;

  OctomapLayer& tree() { return tree_; }
  const OctomapLayer& tree() const { return tree_; }

 private:
  OctomapMapperLayerParams params_;
  OctomapLayer tree_;
};

}  // namespace cairn::mapping
