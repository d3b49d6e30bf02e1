#pragma once

#include "mapstore/map_store.h"

/// @file
/// The production ProfileDeriver: the mapping core's DeriveProfileLayers and JudgeObstacle
/// with their default parameters, keyed by mapping::kMappingCodeVersion. Lives in its own
/// library (cairn::mapstore_mapping) so the store core does not depend on the mapping core.

namespace cairn::mapstore {

/// A deriver backed by cairn::mapping.
ProfileDeriver MappingDeriver();

}  // namespace cairn::mapstore
