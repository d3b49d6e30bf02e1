#include "planner/local/critic_registry.h"

#include <cmath>
#include <sstream>

#include "common/check.h"

namespace cairn::planner {

bool CriticParamReader::Get(const std::string& key, double* value) {
  const auto it = config_.params.find(key);
  if (it == config_.params.end()) return false;
  used_.insert(key);
  CAIRN_THROW_UNLESS(std::isfinite(it->second),
                     config_.name << "." << key << " must be finite, got " << it->second);
  *value = it->second;
  return true;
}

bool CriticParamReader::Get(const std::string& key, bool* value) {
  double number = 0.0;
  if (!Get(key, &number)) return false;
  CAIRN_THROW_UNLESS(
      number == 0.0 || number == 1.0,
      config_.name << "." << key << " must be true or false (1 or 0), got " << number);
  *value = number == 1.0;
  return true;
}

void CriticParamReader::Finish() const {
  for (const auto& [key, value] : config_.params) {
    CAIRN_THROW_UNLESS(used_.count(key) > 0,
                       "unknown key '" << key << "' for critic '" << config_.name << "'");
  }
}

void CriticRegistry::Add(const std::string& name, CriticFactory factory) {
  CAIRN_THROW_UNLESS(!name.empty(), "a critic needs a name");
  CAIRN_THROW_UNLESS(factory != nullptr, "critic '" << name << "' needs a factory");
  CAIRN_THROW_UNLESS(factories_.count(name) == 0, "critic '" << name << "' is registered twice");
  factories_.emplace(name, std::move(factory));
}

std::vector<std::string> CriticRegistry::names() const {
  std::vector<std::string> out;
  for (const auto& [name, factory] : factories_) out.push_back(name);
  return out;
}

std::unique_ptr<TrajectoryCritic> CriticRegistry::Make(const CriticConfig& config,
                                                       const CriticSetup& setup) const {
  const auto it = factories_.find(config.name);
  if (it == factories_.end()) {
    std::ostringstream known;
    for (const auto& [name, factory] : factories_) known << " " << name;
    CAIRN_THROW_UNLESS(false, "unknown critic '" << config.name << "'; known:" << known.str());
  }
  CAIRN_THROW_UNLESS(std::isfinite(config.scale) && config.scale >= 0.0,
                     "critic '" << config.name << "': scale must be finite and >= 0");
  std::unique_ptr<TrajectoryCritic> critic = it->second(config, setup);
  CAIRN_DEMAND(critic != nullptr && critic->name() == config.name);
  return critic;
}

void CriticRegistry::Check(const CriticConfig& config) const { Make(config, CriticSetup{}); }

namespace {

// The shipped critics' keys (config/navigator/navigator.yaml lists them with their defaults).

std::unique_ptr<TrajectoryCritic> MakeSpeed(const CriticConfig& c, const CriticSetup& s) {
  CriticParamReader(c).Finish();
  return std::make_unique<SpeedCritic>(c.scale, s.limits.max_vel_x_mps);
}

std::unique_ptr<TrajectoryCritic> MakeOscillation(const CriticConfig& c, const CriticSetup&) {
  CriticParamReader reader(c);
  double reset_dist_m = 0.05;
  double reset_angle_rad = 0.2;
  reader.Get("reset_dist_m", &reset_dist_m);
  reader.Get("reset_angle_rad", &reset_angle_rad);
  reader.Finish();
  CAIRN_THROW_UNLESS(reset_dist_m > 0.0, "oscillation.reset_dist_m must be positive");
  CAIRN_THROW_UNLESS(reset_angle_rad > 0.0, "oscillation.reset_angle_rad must be positive");
  return std::make_unique<OscillationCritic>(c.scale, reset_dist_m, reset_angle_rad);
}

std::unique_ptr<TrajectoryCritic> MakeGoalDist(const CriticConfig& c, const CriticSetup&) {
  CriticParamReader(c).Finish();
  return std::make_unique<GoalDistCritic>(c.scale);
}

std::unique_ptr<TrajectoryCritic> MakePathAlign(const CriticConfig& c, const CriticSetup&) {
  CriticParamReader reader(c);
  double forward_point_distance_m = 0.325;  // Nav2's forward_point_distance
  reader.Get("forward_point_distance_m", &forward_point_distance_m);
  reader.Finish();
  CAIRN_THROW_UNLESS(forward_point_distance_m >= 0.0,
                     "path_align.forward_point_distance_m must be >= 0");
  return std::make_unique<PathAlignCritic>(c.scale, forward_point_distance_m);
}

std::unique_ptr<TrajectoryCritic> MakeClearance(const CriticConfig& c, const CriticSetup& s) {
  CriticParamReader reader(c);
  ClearanceCritic::Params p;
  reader.Get("admissible_braking", &p.admissible_braking);
  reader.Get("braking_margin_s", &p.margin_s);
  reader.Get("inflation_m", &p.inflation_m);
  reader.Finish();
  CAIRN_THROW_UNLESS(p.margin_s >= 0.0, "clearance.braking_margin_s must not be negative");
  CAIRN_THROW_UNLESS(p.inflation_m >= 0.0, "clearance.inflation_m must not be negative");
  p.sim_step_s = s.generator.sim_step_s;
  p.acc_lim_x_mps2 = s.limits.acc_lim_x_mps2;
  p.acc_lim_theta_radps2 = s.limits.acc_lim_theta_radps2;
  // As far as the fastest sample goes over the horizon, plus the footprint's reach.
  p.path_reach_m = s.limits.max_vel_x_mps * s.generator.sim_time_s + 0.3;
  return std::make_unique<ClearanceCritic>(c.scale, p);
}

CriticRegistry MakeBuiltinCritics() {
  CriticRegistry r;
  r.Add("speed", MakeSpeed);
  r.Add("oscillation", MakeOscillation);
  r.Add("goal_dist", MakeGoalDist);
  r.Add("path_align", MakePathAlign);
  r.Add("clearance", MakeClearance);
  return r;
}

}  // namespace

const CriticRegistry& BuiltinCritics() {
  static const CriticRegistry registry = MakeBuiltinCritics();
  return registry;
}

std::vector<CriticConfig> DefaultCritics() {
  return {{"speed", 0.4, {}},
          {"oscillation", 0.2, {}},
          {"goal_dist", 1.5, {}},
          {"path_align", 1.0, {}},
          {"clearance", 1.0, {}}};
}

}  // namespace cairn::planner
