#include "services/mapping/dynamic_layers.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>

#include <png.h>

#include "common/check.h"
#include "common/yaml_reader.h"

namespace cairn::mapping {

namespace {

constexpr uint8_t kUntouched = 0;
constexpr uint8_t kMarked = 1;
constexpr uint8_t kCleared = 2;

const std::array<int8_t, 256>& OccupancyTable() {
  static const std::array<int8_t, 256> table = [] {
    std::array<int8_t, 256> t{};
    for (int c = 0; c < 256; ++c) {
      if (c == 0) {
        t[c] = 0;
      } else if (c == 253) {
        t[c] = 99;
      } else if (c == 254) {
        t[c] = 100;
      } else if (c == 255) {
        t[c] = kOccupancyUnknown;
      } else {
        t[c] = static_cast<int8_t>(1 + (97 * (c - 1)) / 251);
      }
    }
    return t;
  }();
  return table;
}

int8_t ToOccupancy(float value) {
  if (std::isnan(value)) return kOccupancyUnknown;
  return static_cast<int8_t>(std::clamp(std::lround(value), 0L, 100L));
}

float ToFloat(int8_t og) {
  return og < 0 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(og);
}

}  // namespace

int8_t CostToOccupancy(uint8_t cost) { return OccupancyTable()[cost]; }

void DynamicLayersParams::Validate() const {
  CAIRN_THROW_UNLESS(cost_inc >= 1 && cost_inc <= 254,
                     "dynamic cost_inc must be in [1, 254], got " << cost_inc);
  CAIRN_THROW_UNLESS(cost_dec >= 1 && cost_dec <= 254,
                     "dynamic cost_dec must be in [1, 254], got " << cost_dec);
  CAIRN_THROW_UNLESS(std::isfinite(min_length_m) && min_length_m >= 0.0,
                     "dynamic min_length_m must be >= 0, got " << min_length_m);
  CAIRN_THROW_UNLESS(
      std::isfinite(max_length_m) && max_length_m > min_length_m,
      "dynamic max_length_m must be finite and above min_length_m, got " << max_length_m);
  CAIRN_THROW_UNLESS(std::isfinite(update_hz) && update_hz > 0.0,
                     "dynamic update_hz must be positive, got " << update_hz);
  CAIRN_THROW_UNLESS(longterm_add_og >= 0 && longterm_add_og < 100,
                     "dynamic longterm_add_og must be in [0, 100), got " << longterm_add_og);
  CAIRN_THROW_UNLESS(longterm_free_og >= 0 && longterm_free_og <= 100,
                     "dynamic longterm_free_og must be in [0, 100], got " << longterm_free_og);
  CAIRN_THROW_UNLESS(longterm_cost_dec >= 1 && longterm_cost_dec <= 100,
                     "dynamic longterm_cost_dec must be in [1, 100], got " << longterm_cost_dec);
  CAIRN_THROW_UNLESS(static_wall_og >= 0 && static_wall_og <= 100,
                     "dynamic static_wall_og must be in [0, 100], got " << static_wall_og);
}

// ---------------------------------------------------------------------------------------------
// Layers

DynamicLayers::DynamicLayers(const common::GridMap& static_map, const DynamicLayersParams& params,
                             const std::string& layer)
    : params_(params), geometry_(static_map.geometry()) {
  params_.Validate();
  CAIRN_THROW_UNLESS(geometry_.num_cells() > 0, "the static map has no cells");
  const common::Layer& values = static_map.at(layer);
  const size_t n = static_cast<size_t>(geometry_.num_cells());
  static_og_.resize(n);
  for (size_t i = 0; i < n; ++i) static_og_[i] = ToOccupancy(values.data()[i]);
  short_cost_.assign(n, kCostUnknown);
  long_og_ = static_og_;  // seed: the long-term map starts as the static map
  step_state_.assign(n, kUntouched);
}

size_t DynamicLayers::Index(const common::CellIndex& cell) const {
  CAIRN_DEMAND(geometry_.Contains(cell));
  return static_cast<size_t>(geometry_.LinearIndex(cell));
}

int8_t DynamicLayers::FinalOccupancy(const common::CellIndex& cell) const {
  const size_t i = Index(cell);
  return std::max(CostToOccupancy(short_cost_[i]), long_og_[i]);
}

std::vector<int8_t> DynamicLayers::final_occupancy() const {
  std::vector<int8_t> out(long_og_.size());
  const auto& table = OccupancyTable();
  for (size_t i = 0; i < out.size(); ++i) out[i] = std::max(table[short_cost_[i]], long_og_[i]);
  return out;
}

void DynamicLayers::SetShortTermCost(const common::CellIndex& cell, uint8_t cost) {
  CAIRN_THROW_UNLESS(geometry_.Contains(cell),
                     "cell (" << cell.ix << ", " << cell.iy << ") is outside the dynamic layers");
  short_cost_[Index(cell)] = cost;
}

void DynamicLayers::SetLongTermOccupancy(const common::CellIndex& cell, int8_t value) {
  CAIRN_THROW_UNLESS(geometry_.Contains(cell),
                     "cell (" << cell.ix << ", " << cell.iy << ") is outside the dynamic layers");
  CAIRN_THROW_UNLESS(value >= -1 && value <= 100,
                     "long-term occupancy must be -1 or 0..100, got " << int{value});
  long_og_[Index(cell)] = value;
}

void DynamicLayers::SetLongTerm(const common::GridMap& map, const std::string& layer) {
  CAIRN_THROW_UNLESS(map.geometry() == geometry_,
                     "the long-term layer's grid differs from the static map's");
  const common::Layer& values = map.at(layer);
  for (size_t i = 0; i < long_og_.size(); ++i) {
    long_og_[i] = ToOccupancy(values.data()[i]);
    // A restored layer never erases a wall of the (possibly newer) static map.
    if (static_og_[i] >= params_.static_wall_og) {
      long_og_[i] = std::max(long_og_[i], static_og_[i]);
    }
  }
}

common::GridMap DynamicLayers::ToGridMap() const {
  common::GridMap map(geometry_);
  common::Layer& st = map.AddLayer(layers::kStaticMap);
  common::Layer& sh = map.AddLayer(layers::kShortTerm);
  common::Layer& lo = map.AddLayer(layers::kLongTerm);
  common::Layer& fi = map.AddLayer(layers::kFinal);
  const auto& table = OccupancyTable();
  for (size_t i = 0; i < long_og_.size(); ++i) {
    const int8_t short_og = table[short_cost_[i]];
    st.data()[i] = ToFloat(static_og_[i]);
    sh.data()[i] = ToFloat(short_og);
    lo.data()[i] = ToFloat(long_og_[i]);
    fi.data()[i] = ToFloat(std::max(short_og, long_og_[i]));
  }
  return map;
}

// ---------------------------------------------------------------------------------------------
// Update

void DynamicLayers::AddReading(const common::Vector2& origin_m, const common::Vector2& direction,
                               double range_m, bool hit, DynamicUpdateStats* stats) {
  // Readings at or below the minimum length (and NaN) are ignored; readings at or beyond the
  // maximum length are clipped to it and mark nothing. Thresholds are compared at float
  // precision, as readings travel as float32.
  const float range_f = static_cast<float>(range_m);
  if (std::isnan(range_m) || range_m < 0.0 || !origin_m.allFinite() || !direction.allFinite() ||
      !(range_f > static_cast<float>(params_.min_length_m))) {
    ++stats->beams_ignored;
    return;
  }
  double length = range_m;
  if (range_f >= static_cast<float>(params_.max_length_m)) {
    length = params_.max_length_m;
    hit = false;
  }
  const common::Vector2 a = geometry_.ContinuousIndexOf(origin_m);
  const common::Vector2 b = geometry_.ContinuousIndexOf(origin_m + direction * length);
  rays_.push_back({a, b, hit});
  ++stats->beams_used;
}

DynamicUpdateStats DynamicLayers::Update(const std::vector<common::LaserScan>& scans) {
  return Update(scans, {});
}

DynamicUpdateStats DynamicLayers::Update(const std::vector<common::LaserScan>& scans,
                                         const std::vector<PlanarRay>& extra_rays) {
  DynamicUpdateStats stats;
  rays_.clear();
  for (const common::LaserScan& scan : scans) {
    const common::Pose3& pose = scan.sensor_pose;
    CAIRN_THROW_UNLESS(pose.position_m.allFinite() && pose.orientation.coeffs().allFinite(),
                       "laser scan has a non-finite sensor pose");
    CAIRN_THROW_UNLESS(std::isfinite(scan.angle_min_rad) && std::isfinite(scan.angle_increment_rad),
                       "laser scan has a non-finite angle_min or angle_increment");
    const Eigen::Matrix3d rotation = pose.orientation.normalized().toRotationMatrix();
    const common::Vector2 origin = pose.position_m.head<2>();
    const double scan_max =
        scan.range_max_m > 0.0 && std::isfinite(scan.range_max_m) ? scan.range_max_m : INFINITY;
    // Every beam (the seed's loop ran to 2·angle_max / increment, which assumed a symmetric
    // scan).
    for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
      double r = scan.ranges_m[i];
      // A no-return (+inf, or at the scan's own maximum) is a reading beyond max_length.
      if (!std::isnan(r) && (std::isinf(r) || r >= scan_max)) r = INFINITY;
      const double angle = scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
      const Eigen::Vector3d dir = rotation * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
      AddReading(origin, dir.head<2>(), r, /*hit=*/true, &stats);
    }
  }
  for (const PlanarRay& ray : extra_rays) {
    const common::Vector2 delta = ray.end_m - ray.origin_m;
    const double length = delta.norm();
    const common::Vector2 direction =
        length > 0.0 ? common::Vector2(delta / length) : common::Vector2::Zero();
    // A ray that is not a hit clears its length (at most max_length) and marks nothing.
    AddReading(ray.origin_m, direction, length, ray.hit, &stats);
  }
  return Step(stats);
}

bool DynamicLayers::Inside(int ix, int iy) const {
  // `<` size: the seed's `<=` wrote one cell past the end of a row.
  return ix >= 0 && iy >= 0 && ix < geometry_.size_x && iy < geometry_.size_y;
}

size_t DynamicLayers::IndexOf(int ix, int iy) const {
  return static_cast<size_t>(ix) + static_cast<size_t>(iy) * static_cast<size_t>(geometry_.size_x);
}

void DynamicLayers::MarkEnds(DynamicUpdateStats* stats) {
  // Each end cell once per step (the seed's unique() on unsorted lists kept duplicates, and
  // every scan between two steps added its own increment).
  for (const Ray& ray : rays_) {
    if (!ray.mark) continue;
    const int ix = static_cast<int>(std::floor(ray.end.x()));
    const int iy = static_cast<int>(std::floor(ray.end.y()));
    if (!Inside(ix, iy)) {
      ++stats->marks_outside;
      continue;
    }
    const size_t i = IndexOf(ix, iy);
    if (step_state_[i] != kUntouched) continue;
    step_state_[i] = kMarked;
    step_touched_.push_back(i);
    uint8_t& c = short_cost_[i];
    if (c == kCostUnknown) {
      c = kCostFree;  // the first hit on an unknown cell only makes it known
    } else if (c < kCostLethal - params_.cost_inc) {
      c = static_cast<uint8_t>(c + params_.cost_inc);
    } else {
      c = kCostLethal;
    }
    ++stats->cells_marked;
  }
}

void DynamicLayers::ClearRays(DynamicUpdateStats* stats) {
  // The cells each ray crosses, from the sensor's cell up to (not including) its end cell, once
  // per step; cells marked in this step are left alone. The exact traversal replaces the seed's
  // staircase walk.
  for (const Ray& ray : rays_) {
    const int end_ix = static_cast<int>(std::floor(ray.end.x()));
    const int end_iy = static_cast<int>(std::floor(ray.end.y()));
    TraverseCells(ray.origin.x(), ray.origin.y(), ray.end.x(), ray.end.y(), [&](int ix, int iy) {
      if (ix == end_ix && iy == end_iy) return false;
      if (!Inside(ix, iy)) return true;
      const size_t i = IndexOf(ix, iy);
      if (step_state_[i] != kUntouched) return true;
      step_state_[i] = kCleared;
      step_touched_.push_back(i);
      uint8_t& c = short_cost_[i];
      if (c == kCostUnknown) {
        c = kCostFree;
      } else if (c >= params_.cost_dec) {
        c = static_cast<uint8_t>(c - params_.cost_dec);
      } else {
        c = kCostFree;
      }
      ++stats->cells_cleared;
      return true;
    });
  }
}

void DynamicLayers::UpdateLongTerm(DynamicUpdateStats* stats) {
  // Every cell: adopt what is surely occupied now, forget what is seen free, never below 0 and
  // never on a wall of the static map.
  const auto& table = OccupancyTable();
  const int8_t dec = static_cast<int8_t>(params_.longterm_cost_dec);
  for (size_t i = 0; i < long_og_.size(); ++i) {
    const int8_t short_og = table[short_cost_[i]];
    const int8_t before = long_og_[i];
    int8_t& long_og = long_og_[i];
    const bool wall = static_og_[i] >= params_.static_wall_og;
    if (short_og > params_.longterm_add_og) {
      // The seed copied the short-term value even onto a wall (lowering 100 to 96).
      long_og = wall ? std::max(short_og, static_og_[i]) : short_og;
    } else if (short_og >= 0 && short_og < params_.longterm_free_og && !wall && long_og >= dec) {
      long_og = static_cast<int8_t>(long_og - dec);
    }
    if (long_og != before) ++stats->long_term_changed;
  }
}

DynamicUpdateStats DynamicLayers::Step(DynamicUpdateStats stats) {
  step_touched_.clear();
  MarkEnds(&stats);
  ClearRays(&stats);
  for (const size_t i : step_touched_) step_state_[i] = kUntouched;
  UpdateLongTerm(&stats);
  ++updates_;
  return stats;
}

// ---------------------------------------------------------------------------------------------
// Static map files

namespace {

// 8192 x 8192 cells (410 m square at 0.05 m); a larger header is taken as corrupt rather than
// allocated.
constexpr int64_t kMaxImageCells = int64_t{1} << 26;

struct GreyImage {
  int width{0};
  int height{0};
  std::vector<uint8_t> grey;   // row-major from the top row
  std::vector<uint8_t> alpha;  // 255 where the image has no alpha
};

common::Status ReadPgm(const std::string& path, GreyImage* image) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return common::NotFoundError("cannot open map image '" + path + "'");
  const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  size_t pos = 0;
  auto next_token = [&](std::string* token) {
    token->clear();
    while (pos < bytes.size()) {
      const char c = bytes[pos];
      if (c == '#') {
        while (pos < bytes.size() && bytes[pos] != '\n') ++pos;
      } else if (std::isspace(static_cast<unsigned char>(c))) {
        ++pos;
      } else {
        break;
      }
    }
    while (pos < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[pos]))) {
      *token += bytes[pos++];
    }
    return !token->empty();
  };
  std::string magic, w, h, m;
  if (!next_token(&magic) || (magic != "P5" && magic != "P2") || !next_token(&w) ||
      !next_token(&h) || !next_token(&m)) {
    return common::CorruptError("'" + path + "' is not a PGM image (P2 or P5)");
  }
  int maxval = 0;
  try {
    image->width = std::stoi(w);
    image->height = std::stoi(h);
    maxval = std::stoi(m);
  } catch (const std::exception&) {
    return common::CorruptError("'" + path + "' has a malformed PGM header");
  }
  if (image->width <= 0 || image->height <= 0 ||
      static_cast<int64_t>(image->width) * image->height > kMaxImageCells || maxval <= 0 ||
      maxval > 65535) {
    return common::CorruptError("'" + path + "' has a PGM size or maxval out of range");
  }
  const size_t n = static_cast<size_t>(image->width) * image->height;
  image->grey.resize(n);
  image->alpha.assign(n, 255);
  auto scale = [maxval](int v) {
    return static_cast<uint8_t>(std::clamp(v, 0, maxval) * 255 / maxval);
  };
  if (magic == "P5") {
    ++pos;  // one whitespace byte after maxval
    const size_t bytes_per = maxval < 256 ? 1 : 2;
    if (bytes.size() < pos + n * bytes_per) {
      return common::CorruptError("'" + path + "' is a truncated PGM image");
    }
    for (size_t i = 0; i < n; ++i) {
      const auto* p = reinterpret_cast<const unsigned char*>(bytes.data() + pos + i * bytes_per);
      image->grey[i] = scale(bytes_per == 1 ? p[0] : (p[0] << 8) | p[1]);
    }
  } else {
    std::string token;
    for (size_t i = 0; i < n; ++i) {
      if (!next_token(&token)) return common::CorruptError("'" + path + "' is a truncated PGM");
      try {
        image->grey[i] = scale(std::stoi(token));
      } catch (const std::exception&) {
        return common::CorruptError("'" + path + "' has a malformed PGM value");
      }
    }
  }
  return common::Status::Ok();
}

common::Status ReadPng(const std::string& path, GreyImage* image) {
  png_image png;
  std::memset(&png, 0, sizeof(png));
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&png, path.c_str())) {
    const std::string why = png.message;
    png_image_free(&png);
    if (!std::filesystem::exists(path)) {
      return common::NotFoundError("cannot open map image '" + path + "'");
    }
    return common::CorruptError("'" + path + "' is not a readable PNG image: " + why);
  }
  if (static_cast<int64_t>(png.width) * png.height > kMaxImageCells) {
    png_image_free(&png);
    return common::CorruptError("'" + path + "' is larger than a map image may be");
  }
  png.format = PNG_FORMAT_RGBA;
  std::vector<uint8_t> rgba(PNG_IMAGE_SIZE(png));
  if (!png_image_finish_read(&png, nullptr, rgba.data(), 0, nullptr)) {
    const std::string why = png.message;
    png_image_free(&png);
    return common::CorruptError("'" + path + "' is a damaged PNG image: " + why);
  }
  image->width = static_cast<int>(png.width);
  image->height = static_cast<int>(png.height);
  const size_t n = static_cast<size_t>(image->width) * image->height;
  image->grey.resize(n);
  image->alpha.resize(n);
  for (size_t i = 0; i < n; ++i) {
    // The mean of the colour channels, as map_server takes it.
    image->grey[i] = static_cast<uint8_t>((rgba[4 * i] + rgba[4 * i + 1] + rgba[4 * i + 2]) / 3);
    image->alpha[i] = rgba[4 * i + 3];
  }
  return common::Status::Ok();
}

}  // namespace

common::Result<common::GridMap> LoadStaticMap(const std::string& yaml_path) {
  std::string image_name, mode = "trinary";
  double resolution = 0.0, occupied_thresh = 0.65, free_thresh = 0.196;
  int negate = 0;
  std::vector<double> origin;
  try {
    common::YamlMap yaml = common::YamlMap::LoadFile(yaml_path);
    image_name = yaml.Require<std::string>("image");
    resolution = yaml.Require<double>("resolution");
    origin = yaml.Require<std::vector<double>>("origin");
    yaml.Get("negate", &negate);
    yaml.Get("occupied_thresh", &occupied_thresh);
    yaml.Get("free_thresh", &free_thresh);
    yaml.Get("mode", &mode);
    yaml.Finish();
    if (origin.size() != 3) yaml.Fail(yaml.Raw("origin"), "origin must be [x, y, yaw]");
  } catch (const common::ConfigError& e) {
    return common::InvalidArgumentError(e.what());
  }
  if (!(resolution > 0.0) || !std::isfinite(resolution) || !std::isfinite(origin[0]) ||
      !std::isfinite(origin[1]) || !std::isfinite(origin[2])) {
    return common::InvalidArgumentError(yaml_path +
                                        ": resolution and origin must be finite, "
                                        "resolution positive");
  }
  if (!(free_thresh >= 0.0 && free_thresh < occupied_thresh && occupied_thresh <= 1.0)) {
    return common::InvalidArgumentError(yaml_path +
                                        ": need 0 <= free_thresh < occupied_thresh <= 1");
  }
  if (mode != "trinary" && mode != "scale" && mode != "raw") {
    return common::InvalidArgumentError(yaml_path + ": mode must be trinary, scale or raw, got '" +
                                        mode + "'");
  }

  std::filesystem::path image_path(image_name);
  if (image_path.is_relative())
    image_path = std::filesystem::path(yaml_path).parent_path() / image_path;
  GreyImage image;
  std::string ext = image_path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  const common::Status status =
      ext == ".png" ? ReadPng(image_path.string(), &image) : ReadPgm(image_path.string(), &image);
  if (!status.ok()) return status;

  common::GridGeometry geometry;
  geometry.resolution_m = resolution;
  geometry.size_x = image.width;
  geometry.size_y = image.height;
  geometry.origin = common::Pose2{origin[0], origin[1], origin[2]};
  common::GridMap map(geometry);
  common::Layer& layer = map.AddLayer(layers::kStaticMap);
  for (int row = 0; row < image.height; ++row) {
    const int iy = image.height - 1 - row;  // the image's first row is the top of the map
    for (int ix = 0; ix < image.width; ++ix) {
      const size_t p = static_cast<size_t>(row) * image.width + ix;
      int value = image.grey[p];
      if (negate) value = 255 - value;
      float cell = std::numeric_limits<float>::quiet_NaN();
      if (mode == "raw") {
        if (value <= 100) cell = static_cast<float>(value);
      } else {
        // map_server: dark is occupied; occ in [0, 1].
        const double occ = (255 - value) / 255.0;
        if (occ > occupied_thresh) {
          cell = 100.f;
        } else if (occ < free_thresh) {
          cell = 0.f;
        } else if (mode == "scale" && image.alpha[p] > 0) {
          const double ratio = (occ - free_thresh) / (occupied_thresh - free_thresh);
          cell = static_cast<float>(static_cast<int>(1 + 98 * ratio));
        }
      }
      layer(ix, iy) = cell;
    }
  }
  return map;
}

DynamicLayersParams ReadDynamicLayersParams(common::YamlMap& m) {
  DynamicLayersParams p;
  m.Get("cost_inc", &p.cost_inc);
  m.Get("cost_dec", &p.cost_dec);
  m.Get("min_length_m", &p.min_length_m);
  m.Get("max_length_m", &p.max_length_m);
  m.Get("update_hz", &p.update_hz);
  m.Get("longterm_add_og", &p.longterm_add_og);
  m.Get("longterm_free_og", &p.longterm_free_og);
  m.Get("longterm_cost_dec", &p.longterm_cost_dec);
  m.Get("static_wall_og", &p.static_wall_og);
  return p;
}

}  // namespace cairn::mapping
