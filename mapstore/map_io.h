#pragma once

/// @file
/// Every file format of the map store, for callers that write or read files directly (a demo
/// drawing PNGs, tests). The formats live one per file under mapstore/io/ and register with
/// the format registry (mapstore/io/format_registry.h) that exports and imports go through:
/// - ROS map_server YAML + PGM (mapstore/io/ros_map.h);
/// - PNG renders of any layer with a legend (mapstore/io/png.h);
/// - OctoMap trees as .bt or .ot (mapstore/io/octomap_files.h);
/// - CSV of obstacles (mapstore/io/obstacles_csv.h);
/// and the safe file writing they share (mapstore/io/files.h).

#include "mapstore/io/files.h"
#include "mapstore/io/format_registry.h"
#include "mapstore/io/obstacles_csv.h"
#include "mapstore/io/occupancy.h"
#include "mapstore/io/octomap_files.h"
#include "mapstore/io/png.h"
#include "mapstore/io/ros_map.h"
