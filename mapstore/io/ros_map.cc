#include "mapstore/io/ros_map.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "common/layers.h"
#include "common/yaml_reader.h"
#include "mapstore/io/files.h"
#include "mapstore/io/format_registry.h"
#include "mapstore/io/occupancy.h"
#include "mapstore/names.h"

namespace cairn::mapstore::io {

namespace fs = std::filesystem;
using common::InvalidArgumentError;
using common::Result;
using common::Status;

namespace {

// The pixel of an occupancy value (0..100, NaN unknown) in a mode.
uint8_t PgmPixel(float v, const RosMapOptions& options) {
  switch (options.mode) {
    case PgmMode::kTrinary:
      if (std::isnan(v)) return 205;
      if (v >= options.occupied_thresh * 100.0) return 0;
      if (v <= options.free_thresh * 100.0) return 254;
      return 205;
    case PgmMode::kScale:
      if (std::isnan(v)) return 205;
      return static_cast<uint8_t>(std::lround(255.0 * (1.0 - std::clamp(v, 0.f, 100.f) / 100.0)));
    case PgmMode::kRaw:
      return std::isnan(v) ? 255 : static_cast<uint8_t>(std::lround(std::clamp(v, 0.f, 100.f)));
  }
  return 205;
}

// The occupancy value of a pixel (0..255 after scaling) as map_server reads it.
float PixelValue(int pixel, bool negate, const RosMapOptions& options) {
  const double occ = options.occupied_thresh, free = options.free_thresh;
  const double p = negate ? pixel / 255.0 : (255 - pixel) / 255.0;
  switch (options.mode) {
    case PgmMode::kTrinary:
      if (p > occ) return 100.f;
      if (p < free) return 0.f;
      return common::kUnknown;
    case PgmMode::kScale:
      if (p > occ) return 100.f;
      if (p < free) return 0.f;
      return static_cast<float>(static_cast<int>(99.0 * (p - free) / (occ - free)));
    case PgmMode::kRaw:
      return pixel <= 100 ? static_cast<float>(pixel) : common::kUnknown;
  }
  return common::kUnknown;
}

// Skips whitespace and '#' comments in a PGM header.
void SkipPgmSpace(const std::string& data, size_t* pos) {
  while (*pos < data.size()) {
    if (std::isspace(static_cast<unsigned char>(data[*pos]))) {
      ++*pos;
    } else if (data[*pos] == '#') {
      while (*pos < data.size() && data[*pos] != '\n') ++*pos;
    } else {
      break;
    }
  }
}

bool ReadPgmInt(const std::string& data, size_t* pos, int* value) {
  SkipPgmSpace(data, pos);
  const size_t start = *pos;
  long v = 0;
  while (*pos < data.size() && std::isdigit(static_cast<unsigned char>(data[*pos]))) {
    v = v * 10 + (data[*pos] - '0');
    if (v > 1000000) return false;
    ++*pos;
  }
  *value = static_cast<int>(v);
  return *pos > start;
}

// The YAML half of a map: geometry, options, the image's name and negate.
struct RosYaml {
  std::string image;
  int negate{0};
};

Result<RosYaml> ReadRosYaml(const std::string& yaml_path, RosMap* map) {
  RosYaml out;
  std::vector<double> origin;
  std::string mode = "trinary";
  try {
    common::YamlMap yaml = common::YamlMap::LoadFile(yaml_path);
    out.image = yaml.Require<std::string>("image");
    map->geometry.resolution_m = yaml.Require<double>("resolution");
    origin = yaml.Require<std::vector<double>>("origin");
    yaml.Get("mode", &mode);
    yaml.Get("negate", &out.negate);
    yaml.Get("occupied_thresh", &map->options.occupied_thresh);
    yaml.Get("free_thresh", &map->options.free_thresh);
    yaml.Finish();
  } catch (const std::exception& e) {
    return InvalidArgumentError(e.what());
  }
  auto parsed_mode = PgmModeFromName(mode);
  if (!parsed_mode.ok()) {
    return InvalidArgumentError(yaml_path + ": " + parsed_mode.status().message());
  }
  map->options.mode = *parsed_mode;
  if (origin.size() != 3 || !std::isfinite(origin[0]) || !std::isfinite(origin[1]) ||
      !std::isfinite(origin[2])) {
    return InvalidArgumentError(yaml_path + ": origin must be [x, y, yaw] with finite values");
  }
  if (!(map->geometry.resolution_m > 0) || !std::isfinite(map->geometry.resolution_m)) {
    return InvalidArgumentError(yaml_path + ": resolution must be positive");
  }
  map->geometry.origin = {origin[0], origin[1], origin[2]};
  return out;
}

// The image must sit in the YAML's folder (or below it).
Result<std::string> ImagePath(const std::string& yaml_path, const std::string& image) {
  std::error_code ec;
  const fs::path folder = fs::path(yaml_path).parent_path();
  const fs::path base = fs::canonical(folder.empty() ? fs::path(".") : folder, ec);
  const fs::path image_path = fs::weakly_canonical(base / image, ec);
  const std::string rel = fs::relative(image_path, base, ec).string();
  if (ec || rel.empty() || rel.rfind("..", 0) == 0 || fs::path(image).is_absolute()) {
    return InvalidArgumentError(yaml_path + ": image '" + image +
                                "' must be a file in the YAML's folder");
  }
  return image_path.string();
}

// Reads the PGM (P5, or P2 as hand-drawn maps often are) into map->occupancy.
Status ReadPgm(const std::string& data, bool negate, RosMap* map) {
  const std::string& path = map->image_path;
  if (data.size() < 2 || data[0] != 'P' || (data[1] != '5' && data[1] != '2')) {
    return InvalidArgumentError(path + " is not a PGM image (P5 or P2)");
  }
  const bool ascii = data[1] == '2';
  size_t pos = 2;
  int w = 0, h = 0, maxval = 0;
  if (!ReadPgmInt(data, &pos, &w) || !ReadPgmInt(data, &pos, &h) ||
      !ReadPgmInt(data, &pos, &maxval) || w <= 0 || h <= 0 || maxval <= 0 || maxval > 255) {
    return InvalidArgumentError(path + ": bad PGM header (8-bit grey images only)");
  }
  ++pos;  // the single whitespace after maxval
  map->geometry.size_x = w;
  map->geometry.size_y = h;
  map->occupancy = common::Layer::Constant(w, h, common::kUnknown);
  for (int row = 0; row < h; ++row) {
    for (int ix = 0; ix < w; ++ix) {
      int pixel = 0;
      if (ascii) {
        if (!ReadPgmInt(data, &pos, &pixel)) {
          return InvalidArgumentError(path + ": truncated PGM data");
        }
      } else {
        if (pos >= data.size()) return InvalidArgumentError(path + ": truncated PGM data");
        pixel = static_cast<uint8_t>(data[pos++]);
      }
      map->occupancy(ix, h - 1 - row) = PixelValue(pixel * 255 / maxval, negate, map->options);
    }
  }
  return Status::Ok();
}

Result<std::vector<std::string>> ExportRos(const ExportContext& ctx, std::optional<PgmMode> mode) {
  const MapInfo& info = ctx.info();
  auto layer = ctx.ChooseLayer(
      {layers::kFinal, layers::kStaticMap, layers::kOccupancy, layers::kOccupancyLogOdds,
       layers::kLongTerm, layers::kShortTerm},
      /*or_first_layer=*/false,
      "map '" + info.name +
          "' has no occupancy layer to export as a ROS map; name a --layer or a --profile (its "
          "cost layer)");
  if (!layer.ok()) return layer.status();
  auto map = ctx.LoadLayer(*layer);
  if (!map.ok()) return map.status();
  auto occupancy = OccupancyPercent(*map, *layer);
  if (!occupancy.ok()) return occupancy.status();
  RosMapOptions options = ctx.options().ros;
  if (mode) options.mode = *mode;
  return WriteRosMap(ctx.options().folder, ctx.Stem(*layer), map->geometry(), *occupancy, options);
}

Status ImportRos(const std::string& path, ImportTarget& target) {
  const ImportOptions& options = target.options();
  Status s = ValidateLayerName(options.layer);
  if (!s.ok()) return s;
  auto ros = ReadRosMap(path);
  if (!ros.ok()) return ros.status();
  if (target.latest() && target.latest()->geometry == ros->geometry) {
    if (!(s = target.StartFromLatest()).ok()) return s;
  } else {
    target.snapshot().base = common::GridMap(ros->geometry);
  }
  MapSnapshot& snapshot = target.snapshot();
  snapshot.base.AddLayer(options.layer) = ros->occupancy;
  if (snapshot.provenance.parameters.empty()) {
    snapshot.provenance.parameters =
        std::string("mode: ") + PgmModeName(ros->options.mode) +
        "\noccupied_thresh: " + std::to_string(ros->options.occupied_thresh) +
        "\nfree_thresh: " + std::to_string(ros->options.free_thresh) + "\n";
  }
  return Status::Ok();
}

}  // namespace

const char* PgmModeName(PgmMode mode) {
  switch (mode) {
    case PgmMode::kTrinary:
      return "trinary";
    case PgmMode::kScale:
      return "scale";
    case PgmMode::kRaw:
      return "raw";
  }
  return "?";
}

Result<PgmMode> PgmModeFromName(const std::string& name) {
  if (name == "trinary") return PgmMode::kTrinary;
  if (name == "scale") return PgmMode::kScale;
  if (name == "raw") return PgmMode::kRaw;
  return InvalidArgumentError("unknown PGM mode '" + name + "' (trinary, scale, raw)");
}

Result<std::vector<std::string>> WriteRosMap(const std::string& folder, const std::string& stem,
                                             const common::GridGeometry& geometry,
                                             const common::Layer& occupancy,
                                             const RosMapOptions& options) {
  Status s = ValidateName("file stem", stem);
  if (!s.ok()) return s;
  if (occupancy.rows() != geometry.size_x || occupancy.cols() != geometry.size_y) {
    return InvalidArgumentError("the layer does not match the geometry");
  }
  if (!(options.free_thresh >= 0 && options.free_thresh < options.occupied_thresh &&
        options.occupied_thresh <= 1)) {
    return InvalidArgumentError("need 0 <= free_thresh < occupied_thresh <= 1");
  }
  auto yaml_path = OutputPath(folder, stem, ".yaml");
  if (!yaml_path.ok()) return yaml_path.status();
  auto pgm_path = OutputPath(folder, stem, ".pgm");
  if (!pgm_path.ok()) return pgm_path.status();

  // PGM rows run from the top of the map (largest y) down, as map_server reads them.
  const int w = geometry.size_x, h = geometry.size_y;
  std::string pgm = "P5\n# cairn map store export (" + std::string(PgmModeName(options.mode)) +
                    ")\n" + std::to_string(w) + " " + std::to_string(h) + "\n255\n";
  const size_t header = pgm.size();
  pgm.resize(header + static_cast<size_t>(w) * h);
  for (int row = 0; row < h; ++row) {
    for (int ix = 0; ix < w; ++ix) {
      pgm[header + static_cast<size_t>(row) * w + ix] =
          static_cast<char>(PgmPixel(occupancy(ix, h - 1 - row), options));
    }
  }
  std::ostringstream yaml;
  yaml << "image: " << stem << ".pgm\n"
       << "mode: " << PgmModeName(options.mode) << "\n"
       << "resolution: " << ShortestDecimal(geometry.resolution_m) << "\n"
       << "origin: [" << ShortestDecimal(geometry.origin.x_m) << ", "
       << ShortestDecimal(geometry.origin.y_m) << ", " << ShortestDecimal(geometry.origin.yaw_rad)
       << "]\n"
       << "negate: 0\n"
       << "occupied_thresh: " << ShortestDecimal(options.occupied_thresh) << "\n"
       << "free_thresh: " << ShortestDecimal(options.free_thresh) << "\n";
  if (!(s = WriteFileAtomically(*pgm_path, pgm)).ok()) return s;
  if (!(s = WriteFileAtomically(*yaml_path, yaml.str())).ok()) return s;
  return std::vector<std::string>{*yaml_path, *pgm_path};
}

Result<RosMap> ReadRosMap(const std::string& yaml_path) {
  RosMap map;
  auto yaml = ReadRosYaml(yaml_path, &map);
  if (!yaml.ok()) return yaml.status();
  auto image_path = ImagePath(yaml_path, yaml->image);
  if (!image_path.ok()) return image_path.status();
  map.image_path = *image_path;
  auto data = ReadFile(map.image_path, 256u << 20);
  if (!data.ok()) return data.status();
  const Status s = ReadPgm(*data, yaml->negate != 0, &map);
  if (!s.ok()) return s;
  return map;
}

void RegisterRosFormats(FormatRegistry* registry) {
  registry->AddExporter({"ros", "ROS map_server YAML + PGM (--mode trinary, scale or raw)",
                         [](const ExportContext& ctx) { return ExportRos(ctx, std::nullopt); }});
  for (PgmMode mode : {PgmMode::kTrinary, PgmMode::kScale, PgmMode::kRaw}) {
    registry->AddExporter(
        {std::string("ros-") + PgmModeName(mode),
         std::string("ROS map_server YAML + PGM in ") + PgmModeName(mode) + " mode",
         [mode](const ExportContext& ctx) { return ExportRos(ctx, mode); }});
  }
  registry->AddImporter({"ros",
                         {".yaml", ".yml"},
                         "ROS map_server YAML + PGM (hand-drawn P2/P5 too) into --layer",
                         ImportRos});
}

}  // namespace cairn::mapstore::io
