#include "planner/places.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <set>

#include <yaml-cpp/yaml.h>

#include "common/yaml_reader.h"
#include "planner/distance_transform.h"
#include "planner/footprint.h"

namespace cairn::planner {

using common::ConfigError;
using common::Pose2;
using common::Vector2;
using common::YamlMap;

namespace {

std::vector<Place> ParsePlaces(const YAML::Node& root, const std::string& where) {
  // (YAML::Node assignment writes through to the referenced node: rebind with reset().)
  YAML::Node list;
  list.reset(root);
  if (root.IsMap()) {
    YamlMap top(root, where);
    if (!top.Has("places")) top.Fail(root, "missing key 'places'");
    list.reset(top.Raw("places"));
    top.Finish();
  }
  YamlMap context(YAML::Node(YAML::NodeType::Map), where);
  if (!list.IsSequence()) context.Fail(list, "places must be a list of {name, polygon}");
  std::vector<Place> places;
  std::set<std::string> names;
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string ctx = "places[" + std::to_string(i) + "]";
    YamlMap entry = context.Wrap(list[i], ctx);
    Place place;
    place.name = entry.Require<std::string>("name");
    if (place.name.empty()) entry.Fail(list[i], ctx + ": empty name");
    if (!names.insert(place.name).second)
      entry.Fail(list[i], "duplicate place '" + place.name + "'");
    YAML::Node polygon = entry.Raw("polygon");
    if (!polygon || !polygon.IsSequence() || polygon.size() < 3) {
      entry.Fail(polygon ? polygon : list[i],
                 "place '" + place.name + "' needs a polygon of at least 3 [x, y] vertices");
    }
    for (const auto& v : polygon) {
      if (!v.IsSequence() || v.size() != 2) entry.Fail(v, "a polygon vertex must be [x, y]");
      double x = 0, y = 0;
      try {
        x = v[0].as<double>();
        y = v[1].as<double>();
      } catch (const YAML::Exception&) {
        entry.Fail(v, "a polygon vertex must be two numbers");
      }
      if (!std::isfinite(x) || !std::isfinite(y)) entry.Fail(v, "polygon vertex is not finite");
      place.polygon_m.emplace_back(x, y);
    }
    entry.Get("label_value", &place.label_value);
    entry.Finish();
    places.push_back(std::move(place));
  }
  return places;
}

}  // namespace

std::vector<Place> LoadPlacesFile(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(path + ": cannot read file");
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  return ParsePlaces(root, path);
}

std::vector<Place> LoadPlacesString(const std::string& yaml, const std::string& where) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw ConfigError(where + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  return ParsePlaces(root, where);
}

const Place* FindPlace(const std::vector<Place>& places, const std::string& name) {
  for (const Place& p : places) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

namespace {

// The cells holding a place's polygon, widened by a margin so that clearance sees nearby walls.
struct CellWindow {
  int x0{0};
  int y0{0};
  int nx{0};
  int ny{0};
  Vector2 centroid{Vector2::Zero()};  // of the polygon's vertices (world)
};

std::optional<CellWindow> PlaceWindow(const Place& place, const CostMap& map) {
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x;
  double max_x = -min_x, max_y = -min_x;
  CellWindow w;
  for (const Vector2& v : place.polygon_m) {
    const Vector2 c = map.ToGridCells(v);
    min_x = std::min(min_x, c.x());
    min_y = std::min(min_y, c.y());
    max_x = std::max(max_x, c.x());
    max_y = std::max(max_y, c.y());
    w.centroid += v;
  }
  w.centroid /= static_cast<double>(place.polygon_m.size());
  const int margin = static_cast<int>(std::ceil(2.0 / map.resolution_m())) + 1;
  w.x0 = static_cast<int>(std::floor(min_x)) - margin;
  w.y0 = static_cast<int>(std::floor(min_y)) - margin;
  w.nx = static_cast<int>(std::floor(max_x)) + margin - w.x0 + 1;
  w.ny = static_cast<int>(std::floor(max_y)) + margin - w.y0 + 1;
  if (w.nx <= 0 || w.ny <= 0 || static_cast<int64_t>(w.nx) * w.ny > 50'000'000) {
    return std::nullopt;
  }
  return w;
}

// Distance (cells) from every cell of the window to the nearest obstacle: a lethal, unknown or
// off-map cell.
Eigen::MatrixXf ObstacleClearance(const CellWindow& w, const CostMap& map) {
  const auto& g = map.geometry();
  GridMask mask(w.nx, w.ny);
  for (int j = 0; j < w.ny; ++j) {
    for (int i = 0; i < w.nx; ++i) {
      const common::CellIndex cell{w.x0 + i, w.y0 + j};
      bool obstacle = true;
      if (g.Contains(cell)) {
        const float v = map.cost()(cell.ix, cell.iy);
        obstacle = std::isnan(v) || v >= map.params().lethal_cost;
      }
      mask(i, j) = obstacle ? 1 : 0;
    }
  }
  return DistanceTransform(mask);
}

struct Candidate {
  double clearance;
  float cost;
  double to_centroid;
  common::CellIndex cell;
};

// The known cells inside the polygon cheaper than max_goal_cost: farthest from obstacles first,
// then cheapest, then nearest the centroid.
std::vector<Candidate> RankCandidates(const Place& place, const CostMap& map, const CellWindow& w,
                                      const Eigen::MatrixXf& clearance,
                                      const PlaceGoalParams& params) {
  const auto& g = map.geometry();
  std::vector<Candidate> candidates;
  for (int j = 0; j < w.ny; ++j) {
    for (int i = 0; i < w.nx; ++i) {
      const common::CellIndex cell{w.x0 + i, w.y0 + j};
      if (!g.Contains(cell)) continue;
      const float v = map.cost()(cell.ix, cell.iy);
      if (std::isnan(v) || v >= params.max_goal_cost) continue;
      const Vector2 center = g.CenterOf(cell);
      if (!PointInPolygon(place.polygon_m, center)) continue;
      candidates.push_back(
          {clearance(i, j) * g.resolution_m, v, (center - w.centroid).norm(), cell});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    if (a.clearance != b.clearance) return a.clearance > b.clearance;
    if (a.cost != b.cost) return a.cost < b.cost;
    return a.to_centroid < b.to_centroid;
  });
  return candidates;
}

}  // namespace

PlaceGoal ResolvePlace(const Place& place, const CostMap& map, const PlaceGoalParams& params) {
  PlaceGoal out;
  const std::optional<CellWindow> window = PlaceWindow(place, map);
  if (!window) {
    out.message = "place '" + place.name + "' has an unusable extent";
    return out;
  }
  const std::vector<Candidate> candidates =
      RankCandidates(place, map, *window, ObstacleClearance(*window, map), params);
  if (candidates.empty()) {
    out.message = "place '" + place.name + "' has no known free cell in the map";
    return out;
  }
  // The best candidate where the footprint fits at some heading.
  const int yaws = std::max(1, params.yaw_samples);
  for (const Candidate& c : candidates) {
    const Vector2 center = map.geometry().CenterOf(c.cell);
    for (int k = 0; k < yaws; ++k) {
      const Pose2 pose{center.x(), center.y(), common::WrapAngle(2.0 * M_PI * k / yaws)};
      if (map.IsValid(pose)) {
        out.found = true;
        out.pose = pose;
        out.clearance_m = c.clearance;
        return out;
      }
    }
  }
  out.message = "the robot does not fit anywhere in place '" + place.name + "'";
  return out;
}

}  // namespace cairn::planner
