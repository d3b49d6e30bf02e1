#include "services/mapping/octomap_mapper_layer.h"

#include "common/check.h"
#include "common/yaml_reader.h"

namespace cairn::mapping {

void OctomapMapperLayerParams::Validate() const {
  tree.Validate();
  CAIRN_THROW_UNLESS(every_revolutions >= 1, "octomap every_revolutions must be >= 1");
  CAIRN_THROW_UNLESS(publish_period_s > 0,
                     "octomap publish_period_s must be positive, got " << publish_period_s);
}

OctomapMapperLayerParams LoadOctomapMapperLayerParams(common::YamlMap& map) {
  OctomapMapperLayerParams p;
  p.tree = ReadOctomapLayerParams(map);
  map.Get("every_revolutions", &p.every_revolutions);
  map.Get("publish_period_s", &p.publish_period_s);
  map.Finish();
  return p;
}

OctomapMapperLayer::OctomapMapperLayer(const OctomapMapperLayerParams& params)
    : params_((params.Validate(), params)), tree_(params.tree) {}

const std::string& OctomapMapperLayer::name() const {
  static const std::string kName = "octomap";
  return kName;
}

LayerSchedule OctomapMapperLayer::schedule() const {
  LayerSchedule s;
  s.publish_period_s = params_.publish_period_s;
  s.every_revolutions = params_.every_revolutions;
  s.own_thread = true;
  return s;
}

void OctomapMapperLayer::OnRevolution(const RevolutionInput& input, RevolutionReport*) {
  tree_.InsertRevolution(input.revolution);
}

common::Status OctomapMapperLayer::WriteOutputs(const std::string& dir, std::ostream& yaml) const {
  const common::Status s = tree_.WriteBinaryFile(dir + "/octomap.bt");
  if (!s.ok()) return s;
  yaml << "octomap: octomap.bt\n";
  return common::Status::Ok();
}

}  // namespace cairn::mapping
