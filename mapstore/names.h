#pragma once

#include <string>

#include "common/status.h"

/// @file
/// Name rules of the map store. Names end up in SQL parameters, LCM channel payloads and file
/// names of exports, so they are checked before anything else happens.

namespace cairn::mapstore {

/// Longest site, map, profile or robot name.
inline constexpr size_t kMaxNameLength = 64;

/// Site, map, profile and robot names: 1 to 64 characters from [A-Za-z0-9_.-], starting with a
/// letter or digit, without "..". `what` names the kind in the message ("map name 'a/b' ...").
common::Status ValidateName(const std::string& what, const std::string& name);

/// Layer names: one or more names as above joined by '/' ("elevation", "cost/pioneer3at"),
/// at most 128 characters.
common::Status ValidateLayerName(const std::string& name);

/// Place names: 1 to 64 characters from [A-Za-z0-9 _.-], starting with a letter or digit
/// ("living room").
common::Status ValidatePlaceName(const std::string& name);

}  // namespace cairn::mapstore
