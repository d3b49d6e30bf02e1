#include "common/robot_profile.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "common/check.h"

namespace cairn::common {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

std::string FormatDouble(double v) {
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

// Reads an angle given either as <stem>_rad or <stem>_deg.
void GetAngle(YamlMap& map, const std::string& stem, double* out_rad) {
  double value = 0.0;
  const bool has_rad = map.Has(stem + "_rad");
  const bool has_deg = map.Has(stem + "_deg");
  if (has_rad && has_deg)
    map.Fail(map.Raw(stem + "_deg"), "give " + stem + " in rad or deg, not both");
  if (has_rad) {
    map.Get(stem + "_rad", out_rad);
  } else if (has_deg) {
    map.Get(stem + "_deg", &value);
    *out_rad = value * kDegToRad;
  }
}

double DistancePointSegment(const Vector2& p, const Vector2& a, const Vector2& b) {
  const Vector2 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

}  // namespace

const char* DriveKindName(DriveKind kind) {
  switch (kind) {
    case DriveKind::kDifferential:
      return "differential";
    case DriveKind::kSkidSteer:
      return "skid_steer";
    case DriveKind::kAuv:
      return "auv";
  }
  return "?";
}

DriveKind DriveKindFromName(const std::string& name) {
  if (name == "differential") return DriveKind::kDifferential;
  if (name == "skid_steer") return DriveKind::kSkidSteer;
  if (name == "auv") return DriveKind::kAuv;
  throw std::invalid_argument("unknown drive '" + name + "' (differential, skid_steer, auv)");
}

void RobotProfile::Validate() const {
  CAIRN_THROW_UNLESS(!name.empty(), "a robot profile needs a name");
  for (char c : name) {
    CAIRN_THROW_UNLESS(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-',
                       "profile name '" << name << "' may hold only letters, digits, '_' and '-'");
  }
  CAIRN_THROW_UNLESS(footprint_m.size() >= 3,
                     "profile '" << name << "': footprint needs at least 3 vertices");
  for (const auto& v : footprint_m) {
    CAIRN_THROW_UNLESS(v.allFinite(), "profile '" << name << "': footprint vertex not finite");
  }
  auto positive = [&](double v, const char* field) {
    CAIRN_THROW_UNLESS(!std::isnan(v) && v > 0.0,
                       "profile '" << name << "': " << field << " must be positive, got " << v);
  };
  auto non_negative = [&](double v, const char* field) {
    CAIRN_THROW_UNLESS(!std::isnan(v) && v >= 0.0,
                       "profile '" << name << "': " << field << " must be >= 0, got " << v);
  };
  positive(max_slope_up_rad, "max_slope_up_rad");
  positive(max_slope_down_rad, "max_slope_down_rad");
  non_negative(max_step_up_m, "max_step_up_m");
  non_negative(max_step_down_m, "max_step_down_m");
  non_negative(max_ditch_width_m, "max_ditch_width_m");
  non_negative(ground_clearance_m, "ground_clearance_m");
  non_negative(max_roughness_m, "max_roughness_m");
  positive(max_vel_x_mps, "max_vel_x_mps");
  CAIRN_THROW_UNLESS(std::isfinite(min_vel_x_mps) && min_vel_x_mps <= 0.0,
                     "profile '" << name << "': min_vel_x_mps must be <= 0, got " << min_vel_x_mps);
  positive(max_vel_theta_radps, "max_vel_theta_radps");
  positive(acc_lim_x_mps2, "acc_lim_x_mps2");
  positive(acc_lim_theta_radps2, "acc_lim_theta_radps2");
  CAIRN_THROW_UNLESS(std::isfinite(max_vel_x_mps) && std::isfinite(max_vel_theta_radps) &&
                         std::isfinite(acc_lim_x_mps2) && std::isfinite(acc_lim_theta_radps2),
                     "profile '" << name << "': velocity and acceleration limits must be finite");
}

std::string RobotProfile::ToYaml() const {
  std::ostringstream out;
  out << "name: " << name << "\n";
  out << "drive: " << DriveKindName(drive) << "\n";
  out << "footprint_m: [";
  for (size_t i = 0; i < footprint_m.size(); ++i) {
    out << (i ? ", " : "") << "[" << FormatDouble(footprint_m[i].x()) << ", "
        << FormatDouble(footprint_m[i].y()) << "]";
  }
  out << "]\n";
  out << "max_slope_up_rad: " << FormatDouble(max_slope_up_rad) << "\n";
  out << "max_slope_down_rad: " << FormatDouble(max_slope_down_rad) << "\n";
  out << "max_step_up_m: " << FormatDouble(max_step_up_m) << "\n";
  out << "max_step_down_m: " << FormatDouble(max_step_down_m) << "\n";
  out << "max_ditch_width_m: " << FormatDouble(max_ditch_width_m) << "\n";
  out << "ground_clearance_m: " << FormatDouble(ground_clearance_m) << "\n";
  out << "max_roughness_m: " << FormatDouble(max_roughness_m) << "\n";
  out << "max_vel_x_mps: " << FormatDouble(max_vel_x_mps) << "\n";
  out << "min_vel_x_mps: " << FormatDouble(min_vel_x_mps) << "\n";
  out << "max_vel_theta_radps: " << FormatDouble(max_vel_theta_radps) << "\n";
  out << "acc_lim_x_mps2: " << FormatDouble(acc_lim_x_mps2) << "\n";
  out << "acc_lim_theta_radps2: " << FormatDouble(acc_lim_theta_radps2) << "\n";
  out << "sensors: [";
  for (size_t i = 0; i < sensors.size(); ++i) out << (i ? ", " : "") << sensors[i];
  out << "]\n";
  return out.str();
}

std::string RobotProfile::ContentHash() const {
  const std::string text = ToYaml();
  return HexDigest(Fnv1a64(text.data(), text.size()));
}

double RobotProfile::CircumscribedRadius() const {
  double r = 0.0;
  for (const auto& v : footprint_m) r = std::max(r, v.norm());
  return r;
}

double RobotProfile::InscribedRadius() const {
  if (footprint_m.size() < 3) return 0.0;
  double r = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < footprint_m.size(); ++i) {
    const Vector2& a = footprint_m[i];
    const Vector2& b = footprint_m[(i + 1) % footprint_m.size()];
    r = std::min(r, DistancePointSegment(Vector2::Zero(), a, b));
  }
  return r;
}

bool RobotProfile::operator==(const RobotProfile& o) const { return ToYaml() == o.ToYaml(); }

RobotProfile LoadRobotProfile(YamlMap& map) {
  RobotProfile p;
  p.name = map.Require<std::string>("name");
  std::string drive = DriveKindName(p.drive);
  map.Get("drive", &drive);
  try {
    p.drive = DriveKindFromName(drive);
  } catch (const std::invalid_argument& e) {
    map.Fail(map.Raw("drive"), e.what());
  }
  if (map.Has("footprint_m")) {
    YAML::Node fp = map.Raw("footprint_m");
    if (!fp.IsSequence()) map.Fail(fp, "footprint_m must be a list of [x, y]");
    for (const auto& v : fp) {
      if (!v.IsSequence() || v.size() != 2) map.Fail(v, "footprint vertex must be [x, y]");
      p.footprint_m.emplace_back(map.As<double>(v[0], "a number"),
                                 map.As<double>(v[1], "a number"));
    }
  } else if (map.Has("length_m") || map.Has("width_m")) {
    p.footprint_m =
        RectangleFootprint(map.Require<double>("length_m"), map.Require<double>("width_m"));
  } else {
    map.Fail(map.Raw("name"), "profile '" + p.name + "' needs footprint_m or length_m/width_m");
  }
  GetAngle(map, "max_slope_up", &p.max_slope_up_rad);
  GetAngle(map, "max_slope_down", &p.max_slope_down_rad);
  map.Get("max_step_up_m", &p.max_step_up_m);
  map.Get("max_step_down_m", &p.max_step_down_m);
  map.Get("max_ditch_width_m", &p.max_ditch_width_m);
  map.Get("ground_clearance_m", &p.ground_clearance_m);
  map.Get("max_roughness_m", &p.max_roughness_m);
  map.Get("max_vel_x_mps", &p.max_vel_x_mps);
  map.Get("min_vel_x_mps", &p.min_vel_x_mps);
  GetAngle(map, "max_vel_theta", &p.max_vel_theta_radps);
  if (map.Has("max_vel_theta_radps")) map.Get("max_vel_theta_radps", &p.max_vel_theta_radps);
  map.Get("acc_lim_x_mps2", &p.acc_lim_x_mps2);
  map.Get("acc_lim_theta_radps2", &p.acc_lim_theta_radps2);
  map.Get("sensors", &p.sensors);
  map.Finish();
  try {
    p.Validate();
  } catch (const std::invalid_argument& e) {
    throw ConfigError(map.Where() + e.what());
  }
  return p;
}

RobotProfile LoadRobotProfileFile(const std::string& path) {
  YamlMap map = YamlMap::LoadFile(path);
  return LoadRobotProfile(map);
}

RobotProfile LoadRobotProfileString(const std::string& yaml, const std::string& where) {
  YamlMap map = YamlMap::FromString(yaml, where);
  return LoadRobotProfile(map);
}

std::vector<Vector2> RectangleFootprint(double length_m, double width_m) {
  const double hx = length_m / 2, hy = width_m / 2;
  return {{hx, hy}, {-hx, hy}, {-hx, -hy}, {hx, -hy}};
}

uint64_t Fnv1a64(const void* data, size_t size, uint64_t seed) {
  const auto* p = static_cast<const unsigned char*>(data);
  uint64_t h = seed;
  for (size_t i = 0; i < size; ++i) {
    h ^= p[i];
    h *= 1099511628211ULL;
  }
  return h;
}

std::string HexDigest(uint64_t value) {
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(value));
  return buf;
}

}  // namespace cairn::common
