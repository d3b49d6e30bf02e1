#include "mapstore/registry_codec.h"

#include <cstring>

namespace cairn::mapstore {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "registries are stored little endian; a big-endian port needs byte swaps here");

namespace {

// Little-endian writer and bounds-checked reader for the registry format.
class Writer {
 public:
  template <typename T>
  void Put(T v) {
    const size_t at = out_.size();
    out_.resize(at + sizeof(T));
    std::memcpy(&out_[at], &v, sizeof(T));
  }
  void PutString(const std::string& s) {
    Put<uint32_t>(static_cast<uint32_t>(s.size()));
    out_ += s;
  }
  std::string Take() { return std::move(out_); }

 private:
  std::string out_;
};

class Reader {
 public:
  explicit Reader(const std::string& in) : in_(in) {}
  template <typename T>
  bool Get(T* v) {
    if (in_.size() - pos_ < sizeof(T)) return false;
    std::memcpy(v, in_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return true;
  }
  bool GetString(std::string* s) {
    uint32_t n = 0;
    if (!Get(&n) || in_.size() - pos_ < n) return false;
    s->assign(in_.data() + pos_, n);
    pos_ += n;
    return true;
  }
  size_t remaining() const { return in_.size() - pos_; }

 private:
  const std::string& in_;
  size_t pos_{0};
};

constexpr uint32_t kRegistryMagicV1 = 0x31475243;  // "CRG1": no parts
// "CRG2": each obstacle ends with its downhill heading and its parts.
constexpr uint32_t kRegistryMagic = 0x32475243;

void PutVerdicts(const std::vector<common::ObstacleVerdict>& verdicts, Writer* w) {
  w->Put<uint32_t>(static_cast<uint32_t>(verdicts.size()));
  for (const auto& v : verdicts) {
    w->PutString(v.profile);
    w->PutString(v.profile_hash);
    w->Put<uint8_t>(v.crossable ? 1 : 0);
    w->PutString(v.reason);
  }
}

bool GetVerdicts(Reader* r, std::vector<common::ObstacleVerdict>* verdicts) {
  uint32_t count = 0;
  // Each verdict takes at least 13 bytes.
  if (!r->Get(&count) || count > r->remaining() / 13) return false;
  verdicts->resize(count);
  for (auto& v : *verdicts) {
    uint8_t crossable = 0;
    if (!r->GetString(&v.profile) || !r->GetString(&v.profile_hash) || !r->Get(&crossable) ||
        !r->GetString(&v.reason)) {
      return false;
    }
    v.crossable = crossable != 0;
  }
  return true;
}

}  // namespace

std::string SerializeParts(const std::vector<common::ObstaclePart>& parts) {
  Writer w;
  w.Put<uint32_t>(static_cast<uint32_t>(parts.size()));
  for (const auto& p : parts) {
    w.Put<int8_t>(static_cast<int8_t>(p.kind));
    w.Put<double>(p.centroid_m.x());
    w.Put<double>(p.centroid_m.y());
    w.Put<double>(p.slope_rad);
    w.Put<double>(p.height_m);
    w.Put<double>(p.width_m);
    w.Put<double>(p.length_m);
    w.Put<double>(p.area_m2);
    w.Put<int32_t>(p.num_cells);
    w.Put<double>(p.heading_in_rad);
    w.PutString(SerializePolygon(p.outline_m));
    PutVerdicts(p.verdicts, &w);
  }
  return w.Take();
}

namespace {
bool GetParts(Reader* r, std::vector<common::ObstaclePart>* parts, std::string* error) {
  uint32_t count = 0;
  if (!r->Get(&count)) {
    *error = "truncated obstacle parts";
    return false;
  }
  if (count > static_cast<uint32_t>(common::kMaxObstacleParts)) {
    *error = "an obstacle has " + std::to_string(count) + " parts (at most " +
             std::to_string(common::kMaxObstacleParts) + ")";
    return false;
  }
  parts->resize(count);
  for (auto& p : *parts) {
    int8_t kind = 0;
    double cx = 0, cy = 0;
    std::string outline;
    const bool ok = r->Get(&kind) && r->Get(&cx) && r->Get(&cy) && r->Get(&p.slope_rad) &&
                    r->Get(&p.height_m) && r->Get(&p.width_m) && r->Get(&p.length_m) &&
                    r->Get(&p.area_m2) && r->Get(&p.num_cells) && r->Get(&p.heading_in_rad) &&
                    r->GetString(&outline) && GetVerdicts(r, &p.verdicts);
    if (!ok || (kind != static_cast<int8_t>(common::ObstacleKind::kRamp) &&
                kind != static_cast<int8_t>(common::ObstacleKind::kStepUp))) {
      *error = "truncated or malformed obstacle part";
      return false;
    }
    p.kind = static_cast<common::ObstacleKind>(kind);
    p.centroid_m = {cx, cy};
    auto polygon = ParsePolygon(outline);
    if (!polygon.ok()) {
      *error = polygon.status().message();
      return false;
    }
    p.outline_m = std::move(polygon).value();
  }
  return true;
}
}  // namespace

common::Result<std::vector<common::ObstaclePart>> ParseParts(const std::string& bytes) {
  Reader r(bytes);
  std::vector<common::ObstaclePart> parts;
  std::string error;
  if (!GetParts(&r, &parts, &error)) return common::CorruptError(error);
  if (r.remaining() != 0) return common::CorruptError("trailing bytes after obstacle parts");
  return parts;
}

std::string SerializeRegistry(const common::ObstacleRegistry& registry) {
  Writer w;
  w.Put<uint32_t>(kRegistryMagic);
  w.Put<int64_t>(registry.map_version);
  w.Put<uint32_t>(static_cast<uint32_t>(registry.obstacles.size()));
  for (const auto& o : registry.obstacles) {
    w.Put<int32_t>(o.id);
    w.Put<int8_t>(static_cast<int8_t>(o.kind));
    w.Put<double>(o.centroid_m.x());
    w.Put<double>(o.centroid_m.y());
    w.Put<double>(o.slope_rad);
    w.Put<double>(o.height_m);
    w.Put<double>(o.width_m);
    w.Put<double>(o.length_m);
    w.Put<double>(o.depth_m);
    w.Put<double>(o.area_m2);
    w.Put<int32_t>(o.num_cells);
    w.PutString(SerializePolygon(o.outline_m));
    PutVerdicts(o.verdicts, &w);
    w.Put<double>(o.downhill_heading_rad);
    w.PutString(SerializeParts(o.parts));
  }
  return w.Take();
}

common::Result<common::ObstacleRegistry> ParseRegistry(const std::string& bytes) {
  Reader r(bytes);
  uint32_t magic = 0, count = 0;
  common::ObstacleRegistry registry;
  if (!r.Get(&magic) || (magic != kRegistryMagic && magic != kRegistryMagicV1) ||
      !r.Get(&registry.map_version) || !r.Get(&count)) {
    return common::CorruptError("not an obstacle registry");
  }
  // Each obstacle takes at least 93 bytes: refuse counts the bytes cannot hold.
  if (count > r.remaining() / 93 + 1) return common::CorruptError("obstacle count too large");
  registry.obstacles.resize(count);
  for (auto& o : registry.obstacles) {
    int8_t kind = 0;
    double cx = 0, cy = 0;
    std::string outline;
    bool ok = r.Get(&o.id) && r.Get(&kind) && r.Get(&cx) && r.Get(&cy) && r.Get(&o.slope_rad) &&
              r.Get(&o.height_m) && r.Get(&o.width_m) && r.Get(&o.length_m) && r.Get(&o.depth_m) &&
              r.Get(&o.area_m2) && r.Get(&o.num_cells) && r.GetString(&outline) &&
              GetVerdicts(&r, &o.verdicts);
    const int max_kind = magic == kRegistryMagicV1 ? 5 : 6;
    if (!ok || kind < 1 || kind > max_kind) {
      return common::CorruptError("truncated or malformed obstacle registry");
    }
    if (magic == kRegistryMagic) {
      std::string parts, error;
      if (!r.Get(&o.downhill_heading_rad) || !r.GetString(&parts)) {
        return common::CorruptError("truncated obstacle heading or parts");
      }
      auto parsed = ParseParts(parts);
      if (!parsed.ok()) return parsed.status();
      o.parts = std::move(parsed).value();
    }
    o.kind = static_cast<common::ObstacleKind>(kind);
    o.centroid_m = {cx, cy};
    auto polygon = ParsePolygon(outline);
    if (!polygon.ok()) return polygon.status();
    o.outline_m = std::move(polygon).value();
  }
  if (r.remaining() != 0) return common::CorruptError("trailing bytes after obstacle registry");
  return registry;
}

std::string SerializePolygon(const std::vector<common::Vector2>& polygon) {
  std::string out(polygon.size() * 2 * sizeof(double), '\0');
  for (size_t i = 0; i < polygon.size(); ++i) {
    const double xy[2] = {polygon[i].x(), polygon[i].y()};
    std::memcpy(&out[i * 2 * sizeof(double)], xy, sizeof(xy));
  }
  return out;
}

common::Result<std::vector<common::Vector2>> ParsePolygon(const std::string& bytes) {
  if (bytes.size() % (2 * sizeof(double)) != 0) {
    return common::CorruptError("polygon blob of " + std::to_string(bytes.size()) +
                                " bytes is not a list of (x, y) doubles");
  }
  std::vector<common::Vector2> polygon(bytes.size() / (2 * sizeof(double)));
  for (size_t i = 0; i < polygon.size(); ++i) {
    double xy[2];
    std::memcpy(xy, &bytes[i * 2 * sizeof(double)], sizeof(xy));
    polygon[i] = {xy[0], xy[1]};
  }
  return polygon;
}

}  // namespace cairn::mapstore
