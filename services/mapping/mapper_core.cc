#include "services/mapping/mapper_core.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "common/check.h"
#include "services/mapping/derive.h"
#include "services/mapping/mapper_layers.h"

namespace cairn::mapping {
namespace {

double Seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

template <typename T>
T* Cast(MapperLayer* layer) {
  return dynamic_cast<T*>(layer);
}

}  // namespace

MapperCore::MapperCore(const MapperCoreParams& params) : params_(params), band_(params.band) {
  params_.Validate();
  for (const std::string& name : params_.layers) AddLayer(MakeMapperLayer(name, params_));
  params_.dynamic.long_term_restore.reset();  // used once by the layer; do not keep a copy
}

void MapperCore::AddLayer(std::unique_ptr<MapperLayer> layer) {
  CAIRN_THROW_UNLESS(layer != nullptr, "no layer");
  CAIRN_THROW_UNLESS(FindLayer(layer->name()) == nullptr,
                     "a mapper layer named '" << layer->name() << "' is listed already");
  takes_band_ |= (layer->inputs() & kObstacleBand) != 0;
  layers_.push_back(std::move(layer));
}

MapperLayer* MapperCore::FindLayer(const std::string& name) const {
  for (const auto& layer : layers_) {
    if (layer->name() == name) return layer.get();
  }
  return nullptr;
}

RevolutionReport MapperCore::ProcessRevolution(const common::LidarRevolution& revolution,
                                               const RobotContext& robot, double time_s) {
  RevolutionReport report;
  const RevolutionInput input{revolution, robot, time_s};
  const int64_t n = ++revolutions_seen_;
  for (const auto& layer : layers_) {
    if ((layer->inputs() & kLidarRevolutions) == 0) continue;
    const LayerSchedule schedule = layer->schedule();
    if (n % schedule.every_revolutions != 0) continue;
    if (schedule.own_thread && defer_own_thread_) {
      report.deferred.push_back(layer.get());
    } else {
      layer->OnRevolution(input, &report);
    }
  }
  if (takes_band_) {
    // The band is measured from the ground under the robot when a layer knows it.
    const auto t0 = std::chrono::steady_clock::now();
    double ground_z = std::numeric_limits<double>::quiet_NaN();
    if (robot.xy_m) {
      for (const auto& layer : layers_) {
        if (auto z = layer->GroundHeightUnder(*robot.xy_m)) {
          ground_z = *z;
          break;
        }
      }
    }
    const std::vector<PlanarRay>& rays = band_.Project(revolution, ground_z, &report.band);
    for (const auto& layer : layers_) {
      if (layer->inputs() & kObstacleBand) layer->OnObstacleBand(rays, &report);
    }
    report.occupancy_s = Seconds(t0, std::chrono::steady_clock::now());
  }
  ++revolutions_;
  if (!revolution.slices.empty()) AdvanceTo(revolution.slices.back().utime);
  return report;
}

void MapperCore::FeedDeferred(MapperLayer* layer, const common::LidarRevolution& revolution,
                              const RobotContext& robot, double time_s) {
  RevolutionReport unused;
  layer->OnRevolution({revolution, robot, time_s}, &unused);
}

void MapperCore::ProcessScan(const common::LaserScan& scan) {
  for (const auto& layer : layers_) {
    if (layer->inputs() & kPlanarScans) layer->OnScan(scan);
  }
  AdvanceTo(scan.utime);
}

void MapperCore::ProcessReading(const SensorReading& reading) {
  for (const auto& layer : layers_) {
    if ((layer->inputs() & kSensorReadings) == 0) continue;
    const std::vector<std::string> streams = layer->ReadingStreams();
    if (std::find(streams.begin(), streams.end(), reading.stream) != streams.end()) {
      layer->OnReading(reading);
    }
  }
  AdvanceTo(reading.utime);
}

std::vector<std::string> MapperCore::ReadingStreams() const {
  std::vector<std::string> streams;
  for (const auto& layer : layers_) {
    if ((layer->inputs() & kSensorReadings) == 0) continue;
    for (const std::string& s : layer->ReadingStreams()) {
      if (std::find(streams.begin(), streams.end(), s) == streams.end()) streams.push_back(s);
    }
  }
  return streams;
}

void MapperCore::AdvanceTo(int64_t utime) {
  for (const auto& layer : layers_) {
    if (layer->inputs() & kSensorTime) layer->AdvanceTo(utime);
  }
}

TerrainMap* MapperCore::terrain() {
  auto* layer = Cast<TerrainMapperLayer>(FindLayer(kTerrainLayerName));
  return layer ? &layer->map() : nullptr;
}
const TerrainMap* MapperCore::terrain() const { return const_cast<MapperCore*>(this)->terrain(); }
OccupancyGrid* MapperCore::occupancy() {
  auto* layer = Cast<OccupancyMapperLayer>(FindLayer(kOccupancyLayerName));
  return layer ? &layer->grid() : nullptr;
}
const OccupancyGrid* MapperCore::occupancy() const {
  return const_cast<MapperCore*>(this)->occupancy();
}
OctomapLayer* MapperCore::octomap() {
  auto* layer = Cast<OctomapMapperLayer>(FindLayer(kOctomapLayerName));
  return layer ? &layer->tree() : nullptr;
}
const OctomapLayer* MapperCore::octomap() const { return const_cast<MapperCore*>(this)->octomap(); }
DynamicLayers* MapperCore::dynamic() {
  auto* layer = Cast<DynamicMapperLayer>(FindLayer(kDynamicLayerName));
  return layer ? &layer->layers() : nullptr;
}
const DynamicLayers* MapperCore::dynamic() const {
  return const_cast<MapperCore*>(this)->dynamic();
}

const common::Status& MapperCore::long_term_restore_status() const {
  static const common::Status kOk;
  const auto* layer = Cast<DynamicMapperLayer>(FindLayer(kDynamicLayerName));
  return layer ? layer->long_term_restore_status() : kOk;
}

common::Status MapperCore::WriteOutputs(const std::string& dir, const std::string& robot,
                                        int64_t revolutions) const {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return common::UnavailableError("cannot create " + dir + ": " + ec.message());
  std::ostringstream yaml;
  yaml << "# cairn-mapper layers: raw little-endian float32, x fastest from the minimum corner\n";
  yaml << "robot: " << robot << "\n";
  yaml << "code_version: " << kMappingCodeVersion << "\n";
  yaml << "revolutions: " << revolutions << "\n";
  for (const auto& layer : layers_) {
    const common::Status s = layer->WriteOutputs(dir, yaml);
    if (!s.ok()) return s;
  }
  std::ofstream out(dir + "/map.yaml", std::ios::trunc);
  out << yaml.str();
  if (!out) return common::UnavailableError("cannot write " + dir + "/map.yaml");
  return common::Status::Ok();
}

void MapperCore::Reset() {
  for (const auto& layer : layers_) layer->Reset();
  revolutions_ = 0;
}

}  // namespace cairn::mapping
