#include "mapstore/map_operations.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "mapstore/blob_codec.h"

namespace cairn::mapstore {

using common::Result;
using common::Status;

namespace {

double MsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The stored obstacles judged for `profile` (or, when the map stored none, those the derivation
// found), each with that profile's verdict only, sorted by id.
common::ObstacleRegistry RegistryFor(const common::ObstacleRegistry& stored,
                                     const common::ObstacleRegistry& derived,
                                     const ProfileDeriver& deriver,
                                     const common::RobotProfile& profile, const std::string& hash,
                                     int64_t version) {
  common::ObstacleRegistry out;
  out.map_version = version;
  const bool use_stored = !stored.obstacles.empty();
  for (const common::Obstacle& source : use_stored ? stored.obstacles : derived.obstacles) {
    common::Obstacle o = source;
    common::ObstacleVerdict verdict;
    const common::ObstacleVerdict* own = use_stored ? nullptr : source.VerdictFor(profile.name);
    verdict = own != nullptr ? *own : deriver.judge(source, profile);
    verdict.profile = profile.name;
    verdict.profile_hash = hash;
    if (verdict.crossable) verdict.reason.clear();
    o.verdicts = {verdict};
    std::vector<common::ObstacleVerdict> parts;
    if (!o.parts.empty() && deriver.judge_parts) parts = deriver.judge_parts(source, profile);
    for (size_t k = 0; k < o.parts.size(); ++k) {
      o.parts[k].verdicts.clear();
      if (k >= parts.size()) continue;
      parts[k].profile = profile.name;
      parts[k].profile_hash = hash;
      o.parts[k].verdicts.push_back(std::move(parts[k]));
    }
    out.obstacles.push_back(std::move(o));
  }
  std::sort(out.obstacles.begin(), out.obstacles.end(),
            [](const common::Obstacle& a, const common::Obstacle& b) { return a.id < b.id; });
  return out;
}

// Derives a profile's layers from the full base of a version (nothing is stored).
Result<DerivedProfile> Derive(const MapStore& store, const ProfileDeriver& deriver,
                              const MapRef& exact, const MapInfo& info,
                              const StoredProfile& profile, double* derive_ms) {
  auto base = store.LoadLayers(exact, {});
  if (!base.ok()) return base.status();
  auto stored = store.LoadObstacles(exact);
  if (!stored.ok()) return stored.status();
  const auto t0 = std::chrono::steady_clock::now();
  ProfileDeriver::Output out;
  try {
    out = deriver.derive(*base, profile.profile);
  } catch (const std::invalid_argument& e) {
    return common::InvalidArgumentError("map '" + info.site + "/" + info.name +
                                        "' cannot be derived for profile '" + profile.profile.name +
                                        "': " + e.what());
  } catch (const std::exception& e) {
    return common::InternalError(std::string("derivation failed: ") + e.what());
  }
  DerivedProfile derived;
  derived.profile_name = profile.profile.name;
  derived.profile_hash = profile.content_hash;
  derived.code_version = deriver.code_version;
  if (out.layers.geometry() != info.geometry) {
    return common::InternalError("the derivation returned layers of another geometry");
  }
  derived.layers = common::GridMap(info.geometry);
  const std::set<std::string> base_names(info.layers.begin(), info.layers.end());
  for (const std::string& name : out.layers.layer_names()) {
    if (!base_names.count(name)) derived.layers.AddLayer(name) = out.layers.at(name);
  }
  derived.registry = RegistryFor(*stored, out.registry, deriver, profile.profile,
                                 profile.content_hash, info.version);
  if (derive_ms != nullptr) *derive_ms = MsSince(t0);
  return derived;
}

common::GridMap CropLayers(const common::GridMap& full, const std::vector<std::string>& names,
                           const std::optional<CellBox>& region) {
  const common::GridGeometry& g = full.geometry();
  const CellBox box = region ? ClipBox(*region, g) : CellBox{0, 0, g.size_x, g.size_y};
  common::GridMap out(SubGeometry(g, box));
  for (const std::string& name : names) {
    out.AddLayer(name) = full.at(name).block(box.min_ix, box.min_iy, box.max_ix - box.min_ix,
                                             box.max_iy - box.min_iy);
  }
  return out;
}

std::string Label(const MapInfo& info) {
  return info.site + "/" + info.name + " v" + std::to_string(info.version);
}

std::string Num(double v) {
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%.4g", v);
  return buf;
}

}  // namespace

bool MapDiff::identical() const {
  if (!obstacles.empty()) return false;
  for (const auto& l : layers) {
    if (l.cells_different != 0) return false;
  }
  return true;
}

Result<ProfileView> LoadForProfile(const MapStore& store, const ProfileDeriver* deriver,
                                   const MapRef& ref, const std::string& profile,
                                   const LayerQuery& query) {
  auto info = store.GetMapInfo(ref);
  if (!info.ok()) return info.status();
  const MapRef exact{info->site, info->name, info->version};
  const std::set<std::string> base_names(info->layers.begin(), info->layers.end());
  std::vector<std::string> base_wanted, derived_wanted;
  for (const std::string& name : query.layers) {
    (base_names.count(name) ? base_wanted : derived_wanted).push_back(name);
  }
  const bool all = query.layers.empty();
  if (all) base_wanted = info->layers;

  ProfileView view;
  view.info = *info;
  if (profile.empty() && !derived_wanted.empty()) {
    std::map<std::string, int64_t> known;
    for (const auto& n : info->layers) known[n] = 0;
    return common::NotFoundError(
        "map '" + exact.site + "/" + exact.name + "' version " + std::to_string(exact.version) +
        " has no layer '" + derived_wanted.front() + "' (name a profile to get derived layers)");
  }
  if (base_wanted.empty()) {
    const common::GridGeometry& g = info->geometry;
    const CellBox box =
        query.region ? ClipBox(*query.region, g) : CellBox{0, 0, g.size_x, g.size_y};
    if (box.empty()) return common::InvalidArgumentError("the region does not overlap the map");
    view.layers = common::GridMap(SubGeometry(g, box));
  } else {
    auto base = store.LoadLayers(exact, {base_wanted, query.region});
    if (!base.ok()) return base.status();
    view.layers = std::move(base).value();
  }
  if (profile.empty()) {
    auto obstacles = store.LoadObstacles(exact);
    if (!obstacles.ok()) return obstacles.status();
    view.obstacles = std::move(obstacles).value();
    return view;
  }

  auto stored = store.GetProfile(profile);
  if (!stored.ok()) return stored.status();
  if (deriver == nullptr || !deriver->valid()) {
    return common::UnavailableError("no derivation is available to serve profile '" + profile +
                                    "'");
  }
  auto cached =
      store.FindDerived(exact, stored->content_hash, deriver->code_version,
                        {all ? std::vector<std::string>{} : derived_wanted, query.region});
  if (!cached.ok()) return cached.status();
  DerivedProfile derived;
  if (cached->has_value()) {
    derived = std::move(**cached);
    view.from_cache = true;
  } else {
    auto fresh = Derive(store, *deriver, exact, *info, *stored, &view.derive_ms);
    if (!fresh.ok()) return fresh.status();
    std::vector<std::string> names = all ? fresh->layers.layer_names() : derived_wanted;
    for (const std::string& name : names) {
      if (!fresh->layers.HasLayer(name)) {
        return common::NotFoundError("profile '" + profile + "' has no derived layer '" + name +
                                     "'");
      }
    }
    derived = std::move(fresh).value();
    derived.layers = CropLayers(derived.layers, names, query.region);
  }
  for (const std::string& name : derived.layers.layer_names()) {
    view.layers.AddLayer(name) = derived.layers.at(name);
  }
  view.obstacles = std::move(derived.registry);
  return view;
}

Result<ShareResult> ShareMap(MapStore& store, const ProfileDeriver& deriver, const MapRef& ref,
                             const std::string& target_profile, const WriteContext& ctx) {
  if (!deriver.valid()) return common::UnavailableError("no derivation is available");
  auto info = store.GetMapInfo(ref);
  if (!info.ok()) return info.status();
  const MapRef exact{info->site, info->name, info->version};
  auto target = store.GetProfile(target_profile);
  if (!target.ok()) return target.status();

  ShareResult result;
  result.info = *info;
  result.source_profile = info->provenance.source_profile;
  auto cached = store.FindDerived(exact, target->content_hash, deriver.code_version, {});
  if (!cached.ok()) return cached.status();
  if (cached->has_value()) {
    result.derived = std::move(**cached);
    result.was_cached = true;
  } else {
    auto fresh = Derive(store, deriver, exact, *info, *target, nullptr);
    if (!fresh.ok()) return fresh.status();
    result.derived = std::move(fresh).value();
    Status s = store.PutDerived(exact, result.derived, ctx);
    if (!s.ok()) return s;
  }

  // Verdicts of the source profile: stored with the map, else judged now when the store knows
  // that profile.
  auto stored = store.LoadObstacles(exact);
  if (!stored.ok()) return stored.status();
  std::map<int32_t, const common::Obstacle*> by_id;
  for (const auto& o : stored->obstacles) by_id[o.id] = &o;
  std::optional<StoredProfile> source;
  if (!result.source_profile.empty()) {
    auto p = store.GetProfile(result.source_profile);
    if (p.ok()) source = std::move(p).value();
  }
  for (const common::Obstacle& o : result.derived.registry.obstacles) {
    if (o.verdicts.empty()) continue;
    const common::ObstacleVerdict& target_verdict = o.verdicts.front();
    std::optional<common::ObstacleVerdict> source_verdict;
    auto it = by_id.find(o.id);
    if (it != by_id.end() && !result.source_profile.empty()) {
      if (const auto* v = it->second->VerdictFor(result.source_profile)) source_verdict = *v;
    }
    if (!source_verdict && source) {
      source_verdict = deriver.judge(o, source->profile);
      source_verdict->profile = source->profile.name;
      source_verdict->profile_hash = source->content_hash;
    }
    // One-way counts as its own verdict: a drop one profile may drive down and another may not
    // cross at all is a change.
    const bool differs =
        source_verdict ? (source_verdict->crossable != target_verdict.crossable ||
                          common::IsOneWay(*source_verdict) != common::IsOneWay(target_verdict))
                       : !target_verdict.crossable;
    if (!differs) continue;
    common::Obstacle changed = o;
    changed.verdicts.clear();
    if (source_verdict) changed.verdicts.push_back(*source_verdict);
    changed.verdicts.push_back(target_verdict);
    result.changed.push_back(std::move(changed));
  }
  return result;
}

LayerDiff CompareLayers(const std::string& name_a, const common::Layer& a,
                        const std::string& name_b, const common::Layer& b, double tolerance) {
  LayerDiff d;
  d.layer_a = name_a;
  d.layer_b = name_b;
  if (a.rows() != b.rows() || a.cols() != b.cols()) {
    d.cells_different = std::max<int64_t>(a.size(), b.size());
    return d;
  }
  for (int iy = 0; iy < a.cols(); ++iy) {
    for (int ix = 0; ix < a.rows(); ++ix) {
      const float va = a(ix, iy), vb = b(ix, iy);
      ++d.cells_compared;
      const bool na = std::isnan(va), nb = std::isnan(vb);
      const bool same = (na && nb) || (!na && !nb && std::abs(va - vb) <= tolerance);
      if (!same) {
        ++d.cells_different;
        if (d.examples.size() < 10) d.examples.push_back({ix, iy});
      }
    }
  }
  return d;
}

namespace {

// What differs between two obstacles of one id ("" when nothing does).
std::string ObstacleChange(const common::Obstacle& x, const common::Obstacle* o) {
  std::string what;
  auto cmp = [&](const char* field, double va, double vb) {
    const bool same = (std::isnan(va) && std::isnan(vb)) || std::abs(va - vb) <= 1e-9;
    if (!same)
      what += std::string(what.empty() ? "" : ", ") + field + " " + Num(va) + " -> " + Num(vb);
  };
  if (x.kind != o->kind) {
    what = std::string("kind ") + common::ObstacleKindName(x.kind) + " -> " +
           common::ObstacleKindName(o->kind);
  }
  cmp("slope_rad", x.slope_rad, o->slope_rad);
  cmp("height_m", x.height_m, o->height_m);
  cmp("width_m", x.width_m, o->width_m);
  cmp("length_m", x.length_m, o->length_m);
  cmp("depth_m", x.depth_m, o->depth_m);
  for (const auto& v : o->verdicts) {
    const auto* w = x.VerdictFor(v.profile);
    if (w != nullptr && w->crossable != v.crossable) {
      what += std::string(what.empty() ? "" : ", ") + v.profile + " " +
              (w->crossable ? "crossable -> blocked" : "blocked -> crossable");
    }
  }
  return what;
}

// Layers of two versions of one grid, compared by name.
Status DiffLayers(const MapStore& store, const MapInfo& ia, const MapInfo& ib,
                  const std::vector<std::string>& layers, double tolerance, MapDiff* diff) {
  const MapRef ea{ia.site, ia.name, ia.version}, eb{ib.site, ib.name, ib.version};
  std::set<std::string> names_a(ia.layers.begin(), ia.layers.end());
  std::set<std::string> names_b(ib.layers.begin(), ib.layers.end());
  std::set<std::string> names;
  if (layers.empty()) {
    names.insert(names_a.begin(), names_a.end());
    names.insert(names_b.begin(), names_b.end());
  } else {
    names.insert(layers.begin(), layers.end());
  }
  const int64_t cells = ia.geometry.num_cells();
  for (const std::string& name : names) {
    const bool in_a = names_a.count(name) > 0, in_b = names_b.count(name) > 0;
    if (!in_a && !in_b) return common::NotFoundError("neither map has a layer '" + name + "'");
    if (!in_a || !in_b) {
      LayerDiff d;
      d.layer_a = in_a ? name : "";
      d.layer_b = in_b ? name : "";
      d.cells_different = cells;
      diff->layers.push_back(d);
      continue;
    }
    auto la = store.LoadLayers(ea, {{name}, std::nullopt});
    if (!la.ok()) return la.status();
    auto lb = store.LoadLayers(eb, {{name}, std::nullopt});
    if (!lb.ok()) return lb.status();
    diff->layers.push_back(CompareLayers(name, la->at(name), name, lb->at(name), tolerance));
  }

  return Status::Ok();
}

// Obstacles of two versions, compared by id.
Status DiffObstacles(const MapStore& store, const MapRef& ea, const MapRef& eb, MapDiff* diff) {
  auto oa = store.LoadObstacles(ea);
  if (!oa.ok()) return oa.status();
  auto ob = store.LoadObstacles(eb);
  if (!ob.ok()) return ob.status();
  std::map<int32_t, const common::Obstacle*> ma, mb;
  for (const auto& o : oa->obstacles) ma[o.id] = &o;
  for (const auto& o : ob->obstacles) mb[o.id] = &o;
  for (const auto& [id, o] : ma) {
    if (!mb.count(id)) diff->obstacles.push_back({id, "only in A"});
  }
  for (const auto& [id, o] : mb) {
    auto it = ma.find(id);
    if (it == ma.end()) {
      diff->obstacles.push_back({id, "only in B"});
      continue;
    }
    const std::string what = ObstacleChange(*it->second, o);
    if (!what.empty()) diff->obstacles.push_back({id, what});
  }
  return Status::Ok();
}

}  // namespace

Result<MapDiff> DiffVersions(const MapStore& store, const MapRef& a, const MapRef& b,
                             const std::vector<std::string>& layers, double tolerance) {
  auto ia = store.GetMapInfo(a);
  if (!ia.ok()) return ia.status();
  auto ib = store.GetMapInfo(b);
  if (!ib.ok()) return ib.status();
  if (ia->geometry != ib->geometry) {
    return common::InvalidArgumentError(
        "the two maps have different geometries (" + std::to_string(ia->geometry.size_x) + "x" +
        std::to_string(ia->geometry.size_y) + " vs " + std::to_string(ib->geometry.size_x) + "x" +
        std::to_string(ib->geometry.size_y) + ")");
  }
  MapDiff diff;
  diff.a_label = Label(*ia);
  diff.b_label = Label(*ib);
  Status s = DiffLayers(store, *ia, *ib, layers, tolerance, &diff);
  if (!s.ok()) return s;
  s = DiffObstacles(store, {ia->site, ia->name, ia->version}, {ib->site, ib->name, ib->version},
                    &diff);
  if (!s.ok()) return s;
  return diff;
}

Result<MapDiff> DiffProfiles(const MapStore& store, const ProfileDeriver* deriver,
                             const MapRef& ref, const std::string& profile_a,
                             const std::string& profile_b) {
  const std::string cost_a = "cost/" + profile_a, cost_b = "cost/" + profile_b;
  auto va = LoadForProfile(store, deriver, ref, profile_a, {{cost_a}, std::nullopt});
  if (!va.ok()) return va.status();
  auto vb = LoadForProfile(store, deriver, ref, profile_b, {{cost_b}, std::nullopt});
  if (!vb.ok()) return vb.status();
  MapDiff diff;
  diff.a_label = Label(va->info) + " as " + profile_a;
  diff.b_label = Label(vb->info) + " as " + profile_b;
  diff.layers.push_back(
      CompareLayers(cost_a, va->layers.at(cost_a), cost_b, vb->layers.at(cost_b), 0.0));
  std::map<int32_t, const common::Obstacle*> mb;
  for (const auto& o : vb->obstacles.obstacles) mb[o.id] = &o;
  for (const auto& o : va->obstacles.obstacles) {
    auto it = mb.find(o.id);
    if (it == mb.end() || o.verdicts.empty() || it->second->verdicts.empty()) continue;
    const auto& x = o.verdicts.front();
    const auto& y = it->second->verdicts.front();
    if (x.crossable != y.crossable) {
      diff.obstacles.push_back(
          {o.id, std::string(common::ObstacleKindName(o.kind)) + ": " + profile_a + " " +
                     (x.crossable ? "crossable" : "blocked (" + x.reason + ")") + ", " + profile_b +
                     " " + (y.crossable ? "crossable" : "blocked (" + y.reason + ")")});
    }
  }
  return diff;
}

}  // namespace cairn::mapstore
