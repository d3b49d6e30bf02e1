// cairn-map: the map store's command line (see mapstore/map_cli.h).

#include <cstdlib>

#include "common/log.h"
#include "mapstore/map_cli.h"

int main(int argc, char** argv) {
  if (const char* level = std::getenv("CAIRN_LOG_LEVEL")) {
    if (auto parsed = cairn::common::LogLevelFromName(level)) cairn::common::SetLogLevel(*parsed);
  }
  return cairn::mapstore::RunMapCli(argc, argv);
}
