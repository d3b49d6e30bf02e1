#include "mapstore/mapstore_params.h"

#include <gtest/gtest.h>

namespace cairn::mapstore {
namespace {

using common::ConfigError;
using common::YamlMap;

MapstoreParams Load(const std::string& text) {
  YamlMap root = YamlMap::FromString(text, "mapstore.yaml");
  return LoadMapstoreParams(root);
}

TEST(MapstoreParamsTest, DefaultsHoldWithoutAFileAndEveryKeyIsRead) {
  const MapstoreParams defaults = Load("{}");
  EXPECT_EQ(defaults.service.save_timeout_s, 20.0);
  EXPECT_EQ(defaults.database.wal_autocheckpoint_pages, 16384);  // a long-running writer's
  EXPECT_EQ(MapstoreParams().database.wal_autocheckpoint_pages, 16384);
  const MapstoreParams p = Load(
      "service:\n"
      "  files_root: /srv/maps\n"
      "  save_timeout_s: 7.5\n"
      "  max_staged_bytes: 1000\n"
      "  batch_bytes: 0\n"
      "  compress_reply_tiles: false\n"
      "database:\n"
      "  tile_size_cells: 50\n"
      "  synchronous: FULL\n");
  EXPECT_EQ(p.service.files_root, "/srv/maps");
  EXPECT_EQ(p.service.save_timeout_s, 7.5);
  EXPECT_EQ(p.service.max_staged_bytes, 1000);
  EXPECT_EQ(p.service.batch_bytes, 0);
  EXPECT_FALSE(p.service.compress_reply_tiles);
  EXPECT_EQ(p.database.tile_size_cells, 50);
  EXPECT_EQ(p.database.synchronous, Synchronous::kFull);
  EXPECT_EQ(MapstoreParams().database.synchronous, Synchronous::kNormal);
  const SaveAssemblerParams save = p.service.save();
  EXPECT_EQ(save.save_timeout_s, 7.5);
  EXPECT_EQ(save.max_staged_bytes, 1000);
}

TEST(MapstoreParamsTest, TheShippedFileLoads) {
  const MapstoreParams p =
      LoadMapstoreParamsFile(std::string(CAIRN_SOURCE_DIR) + "/config/mapstore/mapstore.yaml");
  EXPECT_EQ(p.service.reply_tile_size, 100);
  EXPECT_EQ(p.database.wal_autocheckpoint_pages, 16384);
}

TEST(MapstoreParamsTest, UnknownKeysAndBadValuesNameTheirLine) {
  try {
    Load("service:\n  save_timeout_s: 1\n  resend_every_s: 2\n");
    FAIL() << "an unknown key was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("mapstore.yaml:3: unknown key 'service.resend_every_s'"),
              std::string::npos)
        << e.what();
  }
  try {
    Load("service:\n  batch_bytes: 300000\n");
    FAIL() << "an oversized batch was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("service.batch_bytes must be in 0..200000"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(Load("service:\n  save_timeout_s: 0\n"), ConfigError);
  EXPECT_THROW(Load("database:\n  zstd: 3\n"), ConfigError);
  // The durability choice is a word: anything but normal or full is an error, and so is the
  // old boolean key.
  EXPECT_THROW(Load("database:\n  synchronous: extra\n"), ConfigError);
  EXPECT_THROW(Load("database:\n  synchronous_full: true\n"), ConfigError);
  EXPECT_EQ(Load("database:\n  synchronous: normal\n").database.synchronous, Synchronous::kNormal);
  EXPECT_THROW(Load("services: {}\n"), ConfigError);
}

}  // namespace
}  // namespace cairn::mapstore
