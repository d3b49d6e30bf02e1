#include "mapstore/io/obstacles_csv.h"

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "mapstore/io/files.h"
#include "mapstore/io/format_registry.h"

namespace cairn::mapstore::io {

using common::InvalidArgumentError;
using common::Result;
using common::Status;

namespace {

// CSV helpers: quote every text field; backslash-escape ';' '|' '\' inside list fields.
std::string CsvQuote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string EscapeItem(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == ';' || c == '|' || c == '\\') out += '\\';
    if (c == '\n') {
      out += ' ';
      continue;
    }
    out += c;
  }
  return out;
}

// Splits on an unescaped separator, keeping the escapes in the parts.
std::vector<std::string> SplitRaw(const std::string& s, char sep) {
  std::vector<std::string> parts(1);
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '\\' && i + 1 < s.size()) {
      parts.back() += s[i];
      parts.back() += s[++i];
    } else if (s[i] == sep) {
      parts.emplace_back();
    } else {
      parts.back() += s[i];
    }
  }
  if (parts.size() == 1 && parts[0].empty()) parts.clear();
  return parts;
}

std::string Unescape(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '\\' && i + 1 < s.size()) ++i;
    out += s[i];
  }
  return out;
}

// Splits one CSV line (RFC 4180 quoting); false on an unterminated quote.
bool ParseCsvLine(const std::string& line, std::vector<std::string>* fields) {
  fields->assign(1, "");
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        fields->back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        fields->back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields->emplace_back();
    } else if (c != '\r') {
      fields->back() += c;
    }
  }
  return !quoted;
}

bool ParseDouble(const std::string& s, double* out) {
  if (s.empty()) return false;
  char* end = nullptr;
  *out = std::strtod(s.c_str(), &end);
  return end != nullptr && *end == '\0';
}

// A terrace's parts follow it, one row each: `id` numbers the part within the terrace (from 1)
// and `part_of` is the terrace's id (empty on every other row). `downhill_heading_rad` is a ramp's
// or step's (nan: none), empty on part rows.
constexpr char kCsvHeader[] =
    "id,kind,centroid_x_m,centroid_y_m,slope_rad,height_m,width_m,length_m,depth_m,area_m2,"
    "num_cells,outline_m,verdicts,part_of,heading_in_rad,downhill_heading_rad";
constexpr size_t kCsvFields = 16;
// The header of CSVs written before terraces (no parts), still read.
constexpr char kCsvHeaderV1[] =
    "id,kind,centroid_x_m,centroid_y_m,slope_rad,height_m,width_m,length_m,depth_m,area_m2,"
    "num_cells,outline_m,verdicts";
constexpr size_t kCsvFieldsV1 = 13;

Result<common::ObstacleKind> KindFromName(const std::string& name) {
  for (int k = 1; k <= 6; ++k) {
    const auto kind = static_cast<common::ObstacleKind>(k);
    if (name == common::ObstacleKindName(kind)) return kind;
  }
  return InvalidArgumentError("unknown obstacle kind '" + name + "'");
}

std::string Fmt(double v) { return ShortestDecimal(v); }

std::string OutlineField(const std::vector<common::Vector2>& polygon) {
  std::string outline;
  for (const auto& v : polygon) {
    outline += (outline.empty() ? "" : ";") + Fmt(v.x()) + " " + Fmt(v.y());
  }
  return CsvQuote(outline);
}

std::string VerdictsField(const std::vector<common::ObstacleVerdict>& list) {
  std::string verdicts;
  for (const auto& v : list) {
    verdicts += (verdicts.empty() ? "" : ";") + EscapeItem(v.profile) + "|" +
                EscapeItem(v.profile_hash) + "|" + (v.crossable ? "crossable" : "blocked") + "|" +
                EscapeItem(v.reason);
  }
  return CsvQuote(verdicts);
}

// The CSV rows of an obstacle: its own, then one per part.
std::string CsvRows(const common::Obstacle& o) {
  std::ostringstream out;
  out << o.id << "," << common::ObstacleKindName(o.kind) << "," << Fmt(o.centroid_m.x()) << ","
      << Fmt(o.centroid_m.y()) << "," << Fmt(o.slope_rad) << "," << Fmt(o.height_m) << ","
      << Fmt(o.width_m) << "," << Fmt(o.length_m) << "," << Fmt(o.depth_m) << "," << Fmt(o.area_m2)
      << "," << o.num_cells << "," << OutlineField(o.outline_m) << "," << VerdictsField(o.verdicts)
      << ",,," << Fmt(o.downhill_heading_rad) << "\n";
  for (size_t k = 0; k < o.parts.size(); ++k) {
    const common::ObstaclePart& p = o.parts[k];
    out << k + 1 << "," << common::ObstacleKindName(p.kind) << "," << Fmt(p.centroid_m.x()) << ","
        << Fmt(p.centroid_m.y()) << "," << Fmt(p.slope_rad) << "," << Fmt(p.height_m) << ","
        << Fmt(p.width_m) << "," << Fmt(p.length_m) << ",0," << Fmt(p.area_m2) << "," << p.num_cells
        << "," << OutlineField(p.outline_m) << "," << VerdictsField(p.verdicts) << "," << o.id
        << "," << Fmt(p.heading_in_rad) << ",\n";
  }
  return out.str();
}

// The obstacle of one row's 13 fields; `where` ("path:line: ") prefixes errors.
Result<common::Obstacle> ParseObstacle(const std::vector<std::string>& f,
                                       const std::string& where) {
  common::Obstacle o;
  double id = 0, num_cells = 0, cx = 0, cy = 0;
  auto kind = KindFromName(f[1]);
  if (!kind.ok()) return InvalidArgumentError(where + kind.status().message());
  o.kind = *kind;
  if (!ParseDouble(f[0], &id) || !ParseDouble(f[2], &cx) || !ParseDouble(f[3], &cy) ||
      !ParseDouble(f[4], &o.slope_rad) || !ParseDouble(f[5], &o.height_m) ||
      !ParseDouble(f[6], &o.width_m) || !ParseDouble(f[7], &o.length_m) ||
      !ParseDouble(f[8], &o.depth_m) || !ParseDouble(f[9], &o.area_m2) ||
      !ParseDouble(f[10], &num_cells) || id != std::floor(id) || std::abs(id) > 2e9) {
    return InvalidArgumentError(where + "a number does not parse");
  }
  o.id = static_cast<int32_t>(id);
  o.num_cells = static_cast<int32_t>(num_cells);
  o.centroid_m = {cx, cy};
  for (const std::string& vertex : SplitRaw(f[11], ';')) {
    std::istringstream vs(vertex);
    std::string xs, ys;
    double vx = 0, vy = 0;
    if (!(vs >> xs >> ys) || !ParseDouble(xs, &vx) || !ParseDouble(ys, &vy)) {
      return InvalidArgumentError(where + "bad outline vertex '" + vertex + "'");
    }
    o.outline_m.push_back({vx, vy});
  }
  for (const std::string& item : SplitRaw(f[12], ';')) {
    const std::vector<std::string> parts = SplitRaw(item, '|');
    if (parts.size() != 4 || (parts[2] != "crossable" && parts[2] != "blocked")) {
      return InvalidArgumentError(where + "bad verdict '" + item + "'");
    }
    common::ObstacleVerdict v;
    v.profile = Unescape(parts[0]);
    v.profile_hash = Unescape(parts[1]);
    v.crossable = parts[2] == "crossable";
    v.reason = Unescape(parts[3]);
    o.verdicts.push_back(std::move(v));
  }
  return o;
}

Result<std::vector<std::string>> ExportCsv(const ExportContext& ctx) {
  auto registry = ctx.Obstacles();
  if (!registry.ok()) return registry.status();
  auto path = WriteObstaclesCsv(ctx.options().folder, ctx.Stem() + "_obstacles", *registry);
  if (!path.ok()) return path.status();
  return std::vector<std::string>{*path};
}

Status ImportCsv(const std::string& path, ImportTarget& target) {
  Status s = target.StartFromLatest();
  if (!s.ok()) return s;
  auto registry = ReadObstaclesCsv(path);
  if (!registry.ok()) return registry.status();
  target.snapshot().obstacles = std::move(registry).value();
  return Status::Ok();
}

}  // namespace

Result<std::string> WriteObstaclesCsv(const std::string& folder, const std::string& stem,
                                      const common::ObstacleRegistry& registry) {
  auto path = OutputPath(folder, stem, ".csv");
  if (!path.ok()) return path.status();
  std::string out = std::string(kCsvHeader) + "\n";
  for (const common::Obstacle& o : registry.obstacles) out += CsvRows(o);
  const Status s = WriteFileAtomically(*path, out);
  if (!s.ok()) return s;
  return *path;
}

Result<common::ObstacleRegistry> ReadObstaclesCsv(const std::string& path) {
  auto data = ReadFile(path, 64u << 20);
  if (!data.ok()) return data.status();
  std::istringstream in(*data);
  std::string line;
  if (!std::getline(in, line)) line.clear();
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line != kCsvHeader && line != kCsvHeaderV1) {
    return InvalidArgumentError(path + ": not an obstacle CSV (the first line must be '" +
                                kCsvHeader + "')");
  }
  const size_t num_fields = line == kCsvHeader ? kCsvFields : kCsvFieldsV1;
  common::ObstacleRegistry registry;
  int line_no = 1;
  std::vector<std::string> fields;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line == "\r") continue;
    const std::string where = path + ":" + std::to_string(line_no) + ": ";
    if (!ParseCsvLine(line, &fields) || fields.size() != num_fields) {
      return InvalidArgumentError(where + "expected " + std::to_string(num_fields) + " fields");
    }
    auto obstacle = ParseObstacle(fields, where);
    if (!obstacle.ok()) return obstacle.status();
    if (num_fields == kCsvFieldsV1 || fields[13].empty()) {
      if (num_fields == kCsvFields && !fields[14].empty()) {
        return InvalidArgumentError(where + "only a part has a heading_in_rad");
      }
      if (num_fields == kCsvFields && !ParseDouble(fields[15], &obstacle->downhill_heading_rad)) {
        return InvalidArgumentError(where + "downhill_heading_rad does not parse");
      }
      registry.obstacles.push_back(std::move(obstacle).value());
      continue;
    }
    // A part: of the terrace just before it.
    if (registry.obstacles.empty() ||
        registry.obstacles.back().kind != common::ObstacleKind::kTerrace ||
        fields[13] != std::to_string(registry.obstacles.back().id)) {
      return InvalidArgumentError(where + "a part of terrace " + fields[13] +
                                  " must follow that terrace or its other parts");
    }
    common::Obstacle& terrace = registry.obstacles.back();
    double heading = 0;
    if (obstacle->kind != common::ObstacleKind::kRamp &&
        obstacle->kind != common::ObstacleKind::kStepUp) {
      return InvalidArgumentError(where + "a part is a ramp or a step_up, not " + fields[1]);
    }
    if (!ParseDouble(fields[14], &heading)) {
      return InvalidArgumentError(where + "heading_in_rad does not parse");
    }
    if (terrace.parts.size() >= static_cast<size_t>(common::kMaxObstacleParts)) {
      return InvalidArgumentError(where + "a terrace has at most " +
                                  std::to_string(common::kMaxObstacleParts) + " parts");
    }
    common::ObstaclePart p;
    p.kind = obstacle->kind;
    p.centroid_m = obstacle->centroid_m;
    p.outline_m = std::move(obstacle->outline_m);
    p.slope_rad = obstacle->slope_rad;
    p.height_m = obstacle->height_m;
    p.width_m = obstacle->width_m;
    p.length_m = obstacle->length_m;
    p.area_m2 = obstacle->area_m2;
    p.num_cells = obstacle->num_cells;
    p.heading_in_rad = heading;
    p.verdicts = std::move(obstacle->verdicts);
    terrace.parts.push_back(std::move(p));
  }
  for (const auto& o : registry.obstacles) {
    if (o.kind == common::ObstacleKind::kTerrace && o.parts.empty()) {
      return InvalidArgumentError(path + ": terrace " + std::to_string(o.id) + " has no part rows");
    }
  }
  return registry;
}

void RegisterObstaclesCsvFormats(FormatRegistry* registry) {
  registry->AddExporter(
      {"csv", "CSV of obstacles (with --profile: that profile's verdicts)", ExportCsv});
  registry->AddImporter({"csv", {".csv"}, "CSV of obstacles into the latest version", ImportCsv});
}

}  // namespace cairn::mapstore::io
