// cairn-mapstore's inputs: MapstoreService on a real SQLite file (in a temporary folder), with
// the mapping deriver, on memq://. Requests, pushed tiles, batches, manifests, obstacles and
// OctoMap chunks, and a followed robot's live map go through the node's decode and the
// service's real handlers.

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <unistd.h>

#include "mapstore/lcm/mapstore_service.h"
#include "mapstore/mapping_deriver.h"
#include "mapstore/sqlite_map_store.h"
#include "tests/fuzz/bus_channels.h"
#include "tests/fuzz/bus_feed.h"
#include "tests/support/memq_node.h"

namespace {

struct Harness {
  Harness() : node(cairn::testing::MemqNodeOptions("cairn-mapstore")) {
    dir = std::filesystem::temp_directory_path() /
          ("cairn-fuzz-mapstore-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);  // the previous input's database
    std::filesystem::create_directories(dir / "files");
    static const bool cleanup = [this] {
      static const std::string made = dir.string();
      return std::atexit([] { std::filesystem::remove_all(made); }) == 0;
    }();
    (void)cleanup;
    auto opened = cairn::mapstore::SqliteMapStore::Open((dir / "site.db").string());
    if (!opened.ok()) std::abort();
    store = std::move(opened).value();
    cairn::mapstore::MapstoreServiceParams params;
    params.files_root = (dir / "files").string();
    params.save_timeout_s = 0.5;
    params.staging_timeout_s = 1.0;
    service = std::make_unique<cairn::mapstore::MapstoreService>(
        node, *store, cairn::mapstore::MappingDeriver(), params);
  }
  std::filesystem::path dir;
  cairn::runtime::Node node;
  std::unique_ptr<cairn::mapstore::SqliteMapStore> store;
  std::unique_ptr<cairn::mapstore::MapstoreService> service;
};

}  // namespace

// A service and a database per input: inputs stay independent (a finding reproduces from its
// input alone), and the workers stop before the process exits.
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::vector<std::string> channels = cairn::fuzz::MapstoreChannels();
  {
    Harness h;
    cairn::fuzz::FeedBus(h.node, channels, data, size);
  }
  return 0;
}
