#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/status.h"
#include "mapstore/map_store.h"

/// @file
/// Checks and messages shared by the MapStore implementations, so both refuse the same input
/// with the same words.

namespace cairn::mapstore {

/// Wall-clock time in microseconds since the epoch.
int64_t WallUtime();

/// Names, geometry, layers (at least one, valid names), obstacles (kinds, finite centroids),
/// OctoMap (non-empty, positive resolution).
common::Status ValidateSnapshot(const MapSnapshot& snapshot);
/// Name and RobotProfile::Validate.
common::Status ValidateProfile(const common::RobotProfile& profile);
common::Status ValidateDerived(const DerivedProfile& derived);
/// Name, at least three finite vertices.
common::Status ValidatePlace(const Place& place);
/// The site's name and every place (what PutPlaces checks before it writes anything).
common::Status ValidatePlaces(const std::string& site, const std::vector<Place>& places);

/// "map 'site/name' version 3 has no layer 'x' (layers: a, b)".
std::string LayerNotFoundMessage(const MapRef& ref, int64_t version, const std::string& layer,
                                 const std::map<std::string, int64_t>& layers);
/// "no profile 'x' (known: a, b)".
std::string ProfileNotFoundMessage(const std::string& name, const std::vector<std::string>& known);

}  // namespace cairn::mapstore
