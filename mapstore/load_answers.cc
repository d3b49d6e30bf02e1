#include "mapstore/load_answers.h"

#include <algorithm>
#include <set>

#include "common/layers.h"

namespace cairn::mapstore {

using common::Result;
using common::Status;

namespace {

constexpr char kOctomap[] = "octomap";

bool AllIn(const std::vector<std::string>& names, const std::set<std::string>& set) {
  return std::all_of(names.begin(), names.end(),
                     [&](const std::string& l) { return set.count(l) > 0; });
}

bool NoneIn(const std::vector<std::string>& names, const std::set<std::string>& set) {
  return std::none_of(names.begin(), names.end(),
                      [&](const std::string& l) { return set.count(l) > 0; });
}

// Base layers alone, without a profile: the stored blobs as they are (each still checked).
// False when some wanted layer is not a base layer (LoadForProfile explains why).
Result<bool> TryStoredBase(const MapStore& store, const MapInfo& info,
                           const std::vector<std::string>& wanted, int tile_size,
                           LoadAnswer* answer) {
  const std::set<std::string> base(info.layers.begin(), info.layers.end());
  if (!AllIn(wanted, base)) return false;
  const MapRef exact{info.site, info.name, info.version};
  auto tiles = store.LoadStoredTiles(exact, wanted, tile_size);
  if (!tiles.ok()) return tiles.status();
  auto obstacles = store.LoadObstacles(exact);
  if (!obstacles.ok()) return obstacles.status();
  answer->view.info = info;
  answer->view.obstacles = std::move(obstacles).value();
  answer->stored_layers = std::move(tiles).value();
  answer->stored = true;
  return true;
}

// Cached derived layers alone, for a profile: the cache's blobs as they are. False on a cache
// miss, or when a wanted layer is a base layer.
Result<bool> TryStoredDerived(const MapStore& store, const ProfileDeriver& deriver,
                              const LoadRequest& request, const std::vector<std::string>& wanted,
                              LoadAnswer* answer) {
  auto info = store.GetMapInfo(request.ref);
  if (!info.ok()) return info.status();
  const std::set<std::string> base(info->layers.begin(), info->layers.end());
  if (!NoneIn(wanted, base)) return false;
  auto profile_hash = store.GetProfileHash(request.profile);
  if (!profile_hash.ok()) return profile_hash.status();
  const MapRef exact{info->site, info->name, info->version};
  auto cached =
      store.FindDerivedTiles(exact, *profile_hash, deriver.code_version, wanted, request.tile_size);
  if (!cached.ok()) return cached.status();
  if (!cached->has_value()) return false;
  answer->view.info = *info;
  answer->view.obstacles = std::move((*cached)->registry);
  answer->view.from_cache = true;
  answer->stored_layers = std::move((*cached)->layers);
  answer->stored = true;
  return true;
}

}  // namespace

std::vector<std::string> LoadAnswer::layer_names() const {
  std::vector<std::string> names;
  if (stored) {
    for (const StoredLayer& layer : stored_layers) names.push_back(layer.name);
  } else if (!only_octomap) {
    names = view.layers.layer_names();
  }
  return names;
}

std::string LoadAnswer::Summary(bool with_profile) const {
  return std::to_string(layer_names().size()) + " layers" +
         (!with_profile     ? std::string()
          : view.from_cache ? ", derived layers from the cache"
                            : ", derived now (not cached)") +
         (octomap ? ", OctoMap follows" : "");
}

Result<LoadAnswer> AnswerLoad(const MapStore& store, const ProfileDeriver& deriver,
                              const LoadRequest& request) {
  LoadAnswer answer;
  std::vector<std::string> wanted;
  bool want_octomap = false;
  for (const std::string& l : request.layers) {
    if (l == kOctomap) {
      want_octomap = true;
    } else {
      wanted.push_back(l);
    }
  }
  answer.only_octomap = want_octomap && wanted.empty();
  const bool may_send_stored_base =
      !answer.only_octomap && request.profile.empty() && request.may_send_stored;
  if (answer.only_octomap || may_send_stored_base) {
    auto info = store.GetMapInfo(request.ref);
    if (!info.ok()) return info.status();
    answer.view.info = *info;
    if (may_send_stored_base) {
      auto sent = TryStoredBase(store, *info, wanted, request.tile_size, &answer);
      if (!sent.ok()) return sent.status();
    }
  }
  if (!answer.only_octomap && !answer.stored && !request.profile.empty() &&
      request.may_send_stored && !wanted.empty() && deriver.valid()) {
    auto sent = TryStoredDerived(store, deriver, request, wanted, &answer);
    if (!sent.ok()) return sent.status();
  }
  if (!answer.only_octomap && !answer.stored) {
    auto loaded =
        LoadForProfile(store, &deriver, request.ref, request.profile, {wanted, std::nullopt});
    if (!loaded.ok()) return loaded.status();
    answer.view = std::move(loaded).value();
  }
  if (want_octomap) {
    const MapInfo& info = answer.view.info;
    auto octomap = store.LoadOctomap({info.site, info.name, info.version});
    if (!octomap.ok()) return octomap.status();
    answer.octomap = std::move(octomap).value();
  }
  return answer;
}

Result<ObstacleAnswer> AnswerObstacles(const MapStore& store, const ProfileDeriver& deriver,
                                       const MapRef& ref, const std::string& profile) {
  ObstacleAnswer answer;
  auto info = store.GetMapInfo(ref);
  if (!info.ok()) return info.status();
  answer.info = *info;
  if (profile.empty()) {
    auto stored = store.LoadObstacles(ref);
    if (!stored.ok()) return stored.status();
    answer.registry = std::move(stored).value();
    return answer;
  }
  auto view =
      LoadForProfile(store, &deriver, ref, profile, {{layers::CostLayer(profile)}, std::nullopt});
  if (!view.ok()) return view.status();
  answer.registry = std::move(view->obstacles);
  return answer;
}

}  // namespace cairn::mapstore
