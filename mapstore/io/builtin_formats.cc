// The formats cairn-map export/import and OP_EXPORT/OP_IMPORT offer: one registration per
// format file. A new format adds its line here (mapstore/README.md, "Adding an export format").

#include "mapstore/io/directed_csv.h"
#include "mapstore/io/format_registry.h"
#include "mapstore/io/obstacles_csv.h"
#include "mapstore/io/octomap_files.h"
#include "mapstore/io/png.h"
#include "mapstore/io/ros_map.h"

namespace cairn::mapstore::io {

void RegisterBuiltinFormats(FormatRegistry* registry) {
  RegisterRosFormats(registry);
  RegisterPngFormats(registry);
  RegisterOctomapFormats(registry);
  RegisterObstaclesCsvFormats(registry);
  RegisterDirectedCsvFormats(registry);
}

}  // namespace cairn::mapstore::io
