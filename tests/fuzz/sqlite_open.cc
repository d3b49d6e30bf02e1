// SqliteMapStore::Open on a mutated database file: the input is written to a file and opened,
// then every map it lists is read (info, layers, tiles, obstacles, OctoMap) and checked. A
// damaged or foreign file gives a status naming what is wrong; nothing crashes.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "mapstore/sqlite_map_store.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace ms = cairn::mapstore;
  static const std::string path = (std::filesystem::temp_directory_path() /
                                   ("cairn-fuzz-" + std::to_string(::getpid()) + ".db"))
                                      .string();
  for (const char* suffix : {"", "-wal", "-shm", "-journal"}) std::remove((path + suffix).c_str());
  {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  {
    auto store = ms::SqliteMapStore::Open(path);
    if (store.ok()) {
      auto maps = (*store)->ListMaps({});
      if (maps.ok()) {
        for (const ms::MapInfo& info : *maps) {
          const ms::MapRef ref{info.site, info.name, info.version};
          (void)(*store)->GetMapInfo(ref);
          (void)(*store)->LoadLayers(ref, {});
          (void)(*store)->LoadStoredTiles(ref, info.layers);
          (void)(*store)->LoadObstacles(ref);
          (void)(*store)->LoadOctomap(ref);
        }
      }
      (void)(*store)->ListProfiles();
      // The integrity check on a damaged file: pages named by their tables, blobs one by one.
      (void)(*store)->Check();
    }
  }
  for (const char* suffix : {"", "-wal", "-shm", "-journal"}) std::remove((path + suffix).c_str());
  return 0;
}
