#include "mapstore/store_util.h"

#include <chrono>
#include <cmath>

#include "mapstore/names.h"

namespace cairn::mapstore {

using common::InvalidArgumentError;
using common::Status;

namespace {

// True when any cell is +-inf (NaN, unknown, is fine). Exponent bits all set and mantissa zero.
bool HasInfinity(const common::Layer& layer) {
  const uint32_t* bits = reinterpret_cast<const uint32_t*>(layer.data());
  const size_t n = static_cast<size_t>(layer.size());
  uint32_t found = 0;
  for (size_t i = 0; i < n; ++i)
    found |= static_cast<uint32_t>((bits[i] & 0x7fffffffu) == 0x7f800000u);
  return found != 0;
}

}  // namespace

int64_t WallUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

Status ValidateSnapshot(const MapSnapshot& snapshot) {
  Status s = ValidateName("site name", snapshot.site);
  if (!s.ok()) return s;
  if (!(s = ValidateName("map name", snapshot.name)).ok()) return s;
  const Provenance& p = snapshot.provenance;
  if (!p.source_robot.empty() && !(s = ValidateName("source robot", p.source_robot)).ok()) return s;
  if (!p.source_profile.empty() && !(s = ValidateName("source profile", p.source_profile)).ok()) {
    return s;
  }
  if (p.code_version.size() > 256 || p.source_profile_hash.size() > 64) {
    return InvalidArgumentError("provenance code_version or profile hash is too long");
  }
  if (p.parameters.size() > (1u << 20)) {
    return InvalidArgumentError("provenance parameters exceed 1 MB");
  }
  try {
    snapshot.base.geometry().Validate();
  } catch (const std::exception& e) {
    return InvalidArgumentError(std::string("map geometry: ") + e.what());
  }
  const auto& g = snapshot.base.geometry();
  if (!std::isfinite(g.origin.x_m) || !std::isfinite(g.origin.y_m) ||
      !std::isfinite(g.origin.yaw_rad)) {
    return InvalidArgumentError("map origin is not finite");
  }
  if (snapshot.base.layer_names().empty()) {
    return InvalidArgumentError("map '" + snapshot.name + "' has no layers to store");
  }
  for (const std::string& layer : snapshot.base.layer_names()) {
    if (!(s = ValidateLayerName(layer)).ok()) return s;
    if (HasInfinity(snapshot.base.at(layer))) {
      return InvalidArgumentError("layer '" + layer + "' holds infinite values (NaN is unknown)");
    }
  }
  std::map<int32_t, int> ids;
  for (const common::Obstacle& o : snapshot.obstacles.obstacles) {
    const int kind = static_cast<int>(o.kind);
    if (kind < 1 || kind > static_cast<int>(common::ObstacleKind::kTerrace)) {
      return InvalidArgumentError("obstacle " + std::to_string(o.id) + " has unknown kind " +
                                  std::to_string(kind));
    }
    if ((o.kind == common::ObstacleKind::kTerrace) == o.parts.empty() ||
        o.parts.size() > static_cast<size_t>(common::kMaxObstacleParts)) {
      return InvalidArgumentError("obstacle " + std::to_string(o.id) + " has " +
                                  std::to_string(o.parts.size()) + " parts (a terrace has 1 to " +
                                  std::to_string(common::kMaxObstacleParts) +
                                  ", every other kind none)");
    }
    for (const common::ObstaclePart& p : o.parts) {
      if (p.kind != common::ObstacleKind::kRamp && p.kind != common::ObstacleKind::kStepUp) {
        return InvalidArgumentError("a part of obstacle " + std::to_string(o.id) +
                                    " is neither a ramp nor a face");
      }
      for (const common::ObstacleVerdict& v : p.verdicts) {
        if (!(s = ValidateName("verdict profile", v.profile)).ok()) return s;
      }
    }
    if (++ids[o.id] > 1) {
      return InvalidArgumentError("obstacle id " + std::to_string(o.id) + " appears twice");
    }
    if (!o.centroid_m.allFinite()) {
      return InvalidArgumentError("obstacle " + std::to_string(o.id) + " has no finite centroid");
    }
    std::map<std::string, int> profiles;
    for (const common::ObstacleVerdict& v : o.verdicts) {
      if (!(s = ValidateName("verdict profile", v.profile)).ok()) return s;
      if (++profiles[v.profile] > 1) {
        return InvalidArgumentError("obstacle " + std::to_string(o.id) +
                                    " has two verdicts for profile '" + v.profile + "'");
      }
    }
  }
  if (snapshot.octomap) {
    if (snapshot.octomap->bytes.empty()) return InvalidArgumentError("the OctoMap is empty");
    if (!(snapshot.octomap->resolution_m > 0) || !std::isfinite(snapshot.octomap->resolution_m)) {
      return InvalidArgumentError("the OctoMap resolution must be positive");
    }
  }
  return Status::Ok();
}

Status ValidateProfile(const common::RobotProfile& profile) {
  Status s = ValidateName("profile name", profile.name);
  if (!s.ok()) return s;
  try {
    profile.Validate();
  } catch (const std::exception& e) {
    return InvalidArgumentError("profile '" + profile.name + "': " + e.what());
  }
  return Status::Ok();
}

Status ValidateDerived(const DerivedProfile& derived) {
  Status s = ValidateName("profile name", derived.profile_name);
  if (!s.ok()) return s;
  if (derived.profile_hash.empty() || derived.code_version.empty()) {
    return InvalidArgumentError("a derived entry needs a profile hash and a code version");
  }
  for (const std::string& layer : derived.layers.layer_names()) {
    if (!(s = ValidateLayerName(layer)).ok()) return s;
  }
  return Status::Ok();
}

Status ValidatePlace(const Place& place) {
  Status s = ValidatePlaceName(place.name);
  if (!s.ok()) return s;
  if (place.polygon_m.size() < 3) {
    return InvalidArgumentError("place '" + place.name + "' needs at least three vertices");
  }
  for (const auto& v : place.polygon_m) {
    if (!v.allFinite()) {
      return InvalidArgumentError("place '" + place.name + "' has a vertex that is not finite");
    }
  }
  return Status::Ok();
}

Status ValidatePlaces(const std::string& site, const std::vector<Place>& places) {
  Status s = ValidateName("site name", site);
  if (!s.ok()) return s;
  for (const Place& p : places) {
    if (!(s = ValidatePlace(p)).ok()) return s;
  }
  return Status::Ok();
}

std::string LayerNotFoundMessage(const MapRef& ref, int64_t version, const std::string& layer,
                                 const std::map<std::string, int64_t>& layers) {
  std::string known;
  for (const auto& [name, id] : layers) known += (known.empty() ? "" : ", ") + name;
  return "map '" + ref.site + "/" + ref.name + "' version " + std::to_string(version) +
         " has no layer '" + layer + "' (layers: " + known + ")";
}

std::string ProfileNotFoundMessage(const std::string& name, const std::vector<std::string>& known) {
  std::string list;
  for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
  return "no profile '" + name + "' (known: " + (list.empty() ? "none" : list) + ")";
}

}  // namespace cairn::mapstore
