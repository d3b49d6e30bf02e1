#include "services/mapping/explore_mapper_layer.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "common/check.h"
#include "common/yaml_reader.h"
#include "services/explore/explorer_config.h"
#include "services/explore/scan_integration.h"

namespace cairn::mapping {

void ExploreMapperLayerParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(publish_period_s) && publish_period_s > 0.0,
                     "explore.publish_period_s must be > 0");
  CAIRN_THROW_UNLESS(loaded && !explorer_config.empty(),
                     "explore.explorer_config is required (an explorer configuration with an nbv "
                     "section, for example config/explore/unstructured_nbv.yaml)");
  mission.Validate();
}

void ReadExplorerConfig(ExploreMapperLayerParams* p) {
  explore::ExplorerConfig config = explore::LoadExplorerConfigFile(p->explorer_config);
  if (!p->work_area.empty()) config.nbv.work_area = p->work_area;
  try {
    p->mission = config.nbv.ToMissionParams();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("mapper: explore.explorer_config " + p->explorer_config + ": " +
                                e.what());
  }
  p->loaded = true;
}

ExploreMapperLayerParams LoadExploreMapperLayerParams(common::YamlMap& map) {
  ExploreMapperLayerParams p;
  map.Get("explorer_config", &p.explorer_config);
  map.Get("work_area", &p.work_area);
  map.Get("publish_period_s", &p.publish_period_s);
  map.Finish();
  if (!p.explorer_config.empty()) ReadExplorerConfig(&p);  // else Validate names it if listed
  return p;
}

namespace {

const ExploreMapperLayerParams& Validated(const ExploreMapperLayerParams& p) {
  p.Validate();
  return p;
}

}  // namespace

ExploreMapperLayer::ExploreMapperLayer(const ExploreMapperLayerParams& params)
    : params_(Validated(params)),
      info_(params.mission.work_area, params.mission.info),
      assembler_(params.mission.turret),
      layer_names_(info_.ToGridMap().layer_names()) {}

const std::string& ExploreMapperLayer::name() const {
  static const std::string kName = "explore";
  return kName;
}

LayerSchedule ExploreMapperLayer::schedule() const {
  LayerSchedule s;
  s.publish_period_s = params_.publish_period_s;
  return s;
}

void ExploreMapperLayer::OnReading(const SensorReading& reading) {
  const auto* turret = dynamic_cast<const TurretLineReading*>(&reading);
  if (turret == nullptr) return;
  using State = explore::TurretScanAssembler::State;
  const double now_s = static_cast<double>(reading.utime) * 1e-6;
  // Passive: wait for the next sweep's pan 0 unless one is being collected.
  if (assembler_.state() != State::kCollecting) assembler_.Request(now_s);
  std::string event;
  std::optional<explore::OrderedScan> scan =
      assembler_.Add(turret->line, turret->pan_rad, now_s, &event);
  if (!scan && assembler_.state() != State::kCollecting) {
    // The line that broke a sweep (a new sweep's pan 0, say) may start the next one.
    if (assembler_.state() == State::kTimedOut) {
      ++timeouts_;
      assembler_.Request(now_s);
    }
    scan = assembler_.Add(turret->line, turret->pan_rad, now_s);
  }
  if (!event.empty()) events_.push_back("sweep dropped: " + event);
  if (!scan) return;
  const explore::IntegratedScan done =
      explore::IntegrateScan(*scan, params_.mission.Integration(), &info_, &mesh_);
  ++scans_;
  ++version_;
  char line[160];
  std::snprintf(line, sizeof(line),
                "sweep %d at (%.1f, %.1f) on the information map: %lld points, coverage %.1f %%",
                scans_, scan->sensor_origin_m.x(), scan->sensor_origin_m.y(),
                static_cast<long long>(done.points_used), 100.0 * info_.Coverage());
  events_.emplace_back(line);
}

std::vector<std::string> ExploreMapperLayer::TakeEvents() {
  std::vector<std::string> out;
  out.swap(events_);
  return out;
}

void ExploreMapperLayer::Reset() {
  info_ = explore::InfoMap(params_.mission.work_area, params_.mission.info);
  assembler_ = explore::TurretScanAssembler(params_.mission.turret);
  scans_ = 0;
  timeouts_ = 0;
  events_.clear();
  ++version_;
}

std::vector<GridOutput> ExploreMapperLayer::GridOutputs() const {
  std::vector<GridOutput> out;
  for (const std::string& layer : OwnedLayers()) out.push_back({layer, GridEncoding::kFloat});
  return out;
}

std::optional<common::GridMap> ExploreMapperLayer::ExportGrids() const {
  if (scans_ == 0) return std::nullopt;
  return info_.ToGridMap();
}

}  // namespace cairn::mapping
