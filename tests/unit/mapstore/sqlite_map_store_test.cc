// SqliteMapStore behaviour that only a file can show: persistence, refusal of foreign or
// corrupt files, immutability, read-only use, a full disk, concurrent writers, migration.

#include "mapstore/sqlite_map_store.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/layers.h"
#include "mapstore/blob_codec.h"
#include "mapstore/map_operations.h"
#include "mapstore/schema.h"
#include "tests/support/sample_obstacles.h"
#include "tests/unit/mapstore/fake_deriver.h"

namespace cairn::mapstore {
namespace {

namespace fs = std::filesystem;
using common::StatusCode;
using testing::FakeDeriver;
using testing::Profile;
using testing::SameLayer;
using testing::SampleSnapshot;

std::string TempDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::path(CAIRN_BINARY_DIR) / "test-tmp" /
                       (std::string(info->test_suite_name()) + "." + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Runs SQL on a file through a separate raw connection (as another program would).
void RawExec(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  char* error = nullptr;
  const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error);
  const std::string message = error != nullptr ? error : "";
  sqlite3_free(error);
  sqlite3_close(db);
  ASSERT_EQ(rc, SQLITE_OK) << message;
}

std::unique_ptr<SqliteMapStore> OpenOrDie(const std::string& path, SqliteOptions options = {}) {
  auto store = SqliteMapStore::Open(path, options);
  if (!store.ok()) {
    ADD_FAILURE() << store.status().ToString();
    return nullptr;
  }
  return std::move(store).value();
}

const WriteContext kCtx{"unit-test", 0, 0};

SqliteOptions ReadOnly() {
  SqliteOptions o;
  o.read_only = true;
  return o;
}

TEST(SqliteMapStoreTest, PersistsAcrossReopenInWalMode) {
  const std::string path = TempDir() + "/site.db";
  {
    auto dut = OpenOrDie(path);
    ASSERT_TRUE(dut);
    ASSERT_TRUE(dut->SaveMap(SampleSnapshot("corridor"), kCtx).ok());
    EXPECT_EQ(dut->schema_version(), schema::kCurrentVersion);
  }
  auto dut = OpenOrDie(path);
  ASSERT_TRUE(dut);
  auto map = dut->LoadLayers({"lab", "corridor", 0}, {});
  ASSERT_TRUE(map.ok());
  EXPECT_FLOAT_EQ(map->at("elevation")(20, 1), 0.5f + 0.001f);
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(raw, "PRAGMA journal_mode", -1, &st, nullptr);
  ASSERT_EQ(sqlite3_step(st), SQLITE_ROW);
  EXPECT_STREQ(reinterpret_cast<const char*>(sqlite3_column_text(st, 0)), "wal");
  sqlite3_finalize(st);
  sqlite3_close(raw);
}

// A terrace is stored with its parts (headings and verdicts) and read back whole, and a ramp with
// its downhill heading; a parts blob that is not parts is refused where it is read.
TEST(SqliteMapStoreTest, ATerraceIsStoredWithItsParts) {
  const std::string path = TempDir() + "/site.db";
  auto dut = OpenOrDie(path);
  ASSERT_TRUE(dut);
  MapSnapshot snapshot = SampleSnapshot("corridor");
  snapshot.obstacles.obstacles.push_back(cairn::testing::SampleTerrace());
  snapshot.obstacles.obstacles.back().id = 1000;  // after the sample's own
  snapshot.obstacles.obstacles.front().downhill_heading_rad = 0.75;
  const common::Status saved = dut->SaveMap(snapshot, kCtx).status();
  ASSERT_TRUE(saved.ok()) << saved.ToString();
  auto back = dut->LoadObstacles({"lab", "corridor", 0});
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  const common::Obstacle* terrace = nullptr;
  for (const auto& o : back->obstacles) {
    if (o.kind == common::ObstacleKind::kTerrace) terrace = &o;
  }
  ASSERT_NE(terrace, nullptr);
  const common::Obstacle want = cairn::testing::SampleTerrace();
  ASSERT_EQ(terrace->parts.size(), want.parts.size());
  EXPECT_EQ(terrace->parts[1].heading_in_rad, want.parts[1].heading_in_rad);
  EXPECT_EQ(terrace->parts[1].verdicts, want.parts[1].verdicts);
  EXPECT_EQ(terrace->verdicts, want.verdicts);
  EXPECT_TRUE(std::isnan(terrace->downhill_heading_rad));
  for (const auto& o : back->obstacles) {
    if (o.id == snapshot.obstacles.obstacles.front().id) {
      EXPECT_EQ(o.downhill_heading_rad, 0.75);
    }
  }
  dut.reset();
  RawExec(path, "UPDATE obstacles SET parts = x'0500' WHERE kind = 6;");
  auto reopened = OpenOrDie(path);
  ASSERT_TRUE(reopened);
  auto refused = reopened->LoadObstacles({"lab", "corridor", 0});
  EXPECT_EQ(refused.status().code(), StatusCode::kCorrupt);
}

TEST(SqliteMapStoreTest, RefusesFilesThatAreNotCairnDatabases) {
  const std::string dir = TempDir();
  {
    std::ofstream text(dir + "/notes.db");
    text << "this is a shopping list, not a database\n" << std::string(2000, 'x');
  }
  auto text = SqliteMapStore::Open(dir + "/notes.db");
  EXPECT_EQ(text.status().code(), StatusCode::kCorrupt);
  EXPECT_NE(text.status().message().find("not a cairn map database"), std::string::npos)
      << text.status().message();

  RawExec(dir + "/other.db", "CREATE TABLE songs(title TEXT); INSERT INTO songs VALUES('a');");
  auto other = SqliteMapStore::Open(dir + "/other.db");
  EXPECT_EQ(other.status().code(), StatusCode::kCorrupt);
  EXPECT_NE(other.status().message().find("application_id"), std::string::npos);
  // The foreign file was not modified.
  RawExec(dir + "/other.db", "SELECT title FROM songs;");

  const std::string newer = dir + "/newer.db";
  { ASSERT_TRUE(OpenOrDie(newer)); }
  RawExec(newer, "PRAGMA user_version = 99;");
  auto future = SqliteMapStore::Open(newer);
  EXPECT_EQ(future.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(future.status().message().find("newer"), std::string::npos);

  auto missing = SqliteMapStore::Open(dir + "/absent.db", ReadOnly());
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
  EXPECT_FALSE(fs::exists(dir + "/absent.db"));

  // Issue 20 (found by fuzz_sqlite_open): a file with the header of this schema but not its
  // tables made the first query throw "bad SQL ... no such column" (a bug's abort). It is refused
  // at Open, naming what it lacks.
  const std::string damaged = dir + "/damaged.db";
  { ASSERT_TRUE(OpenOrDie(damaged)); }
  RawExec(damaged, "ALTER TABLE map_versions DROP COLUMN code_version;");
  auto lacking = SqliteMapStore::Open(damaged);
  EXPECT_EQ(lacking.status().code(), StatusCode::kCorrupt);
  EXPECT_NE(lacking.status().message().find("map_versions has no column code_version"),
            std::string::npos)
      << lacking.status().message();
}

TEST(SqliteMapStoreTest, CorruptBlobIsRefusedAndReportedByCheck) {
  const std::string path = TempDir() + "/site.db";
  {
    SqliteOptions small_tiles;
    small_tiles.tile_size_cells = 16;
    auto dut = OpenOrDie(path, small_tiles);
    ASSERT_TRUE(dut->SaveMap(SampleSnapshot("corridor"), kCtx).ok());
    ASSERT_TRUE(dut->Check().value().ok);
  }
  // Another program damages one stored tile (past the trigger that forbids it).
  RawExec(
      path,
      "DROP TRIGGER blobs_immutable;"
      "UPDATE blobs SET data = substr(data, 1, 40) || CASE WHEN substr(data, 41, 1) = X'00' "
      "THEN X'01' ELSE X'00' END || substr(data, 42) WHERE id = (SELECT blob_id FROM layer_tiles "
      "t JOIN layers l ON l.id = t.layer_id WHERE l.name = 'elevation' AND t.tile_ix = 1 AND "
      "t.tile_iy = 0);");
  auto dut = OpenOrDie(path);
  auto map = dut->LoadLayers({"lab", "corridor", 0}, {{"elevation"}, std::nullopt});
  EXPECT_EQ(map.status().code(), StatusCode::kCorrupt);
  EXPECT_NE(map.status().message().find("elevation"), std::string::npos) << map.status().message();
  EXPECT_NE(map.status().message().find("tile (1, 0)"), std::string::npos)
      << map.status().message();
  // A load reply's stored tiles are checked as well.
  auto stored = dut->LoadStoredTiles({"lab", "corridor", 0}, {"elevation"});
  EXPECT_EQ(stored.status().code(), StatusCode::kCorrupt);
  EXPECT_NE(stored.status().message().find("tile (1, 0)"), std::string::npos)
      << stored.status().message();
  EXPECT_TRUE(dut->LoadStoredTiles({"lab", "corridor", 0}, {"observation_count"}).ok());
  // The other layer still loads, and so does a region away from the bad tile.
  EXPECT_TRUE(dut->LoadLayers({"lab", "corridor", 0}, {{"observation_count"}, std::nullopt}).ok());
  EXPECT_TRUE(dut->LoadLayers({"lab", "corridor", 0}, {{"elevation"}, CellBox{0, 0, 10, 10}}).ok());
  EXPECT_EQ(dut->LoadLayers({"lab", "corridor", 0}, {{"elevation"}, CellBox{0, 0, 20, 10}})
                .status()
                .code(),
            StatusCode::kCorrupt);
  auto report = dut->Check();
  ASSERT_TRUE(report.ok());
  EXPECT_FALSE(report->ok);
  ASSERT_FALSE(report->problems.empty());
  EXPECT_NE(report->problems[0].find("blob"), std::string::npos) << report->problems[0];
  // ... naming the map, layer and tile the blob holds.
  EXPECT_NE(report->problems[0].find("map lab/corridor v1 layer elevation tile (1, 0)"),
            std::string::npos)
      << report->problems[0];
  // A load's error names the file and how to find every damaged map.
  EXPECT_NE(map.status().message().find("'" + path + "'"), std::string::npos)
      << map.status().message();
  EXPECT_NE(map.status().message().find("cairn-map check"), std::string::npos);
}

// A damaged b-tree page (not a blob's bytes: the page of the blobs table that holds their rows)
// is found by integrity_check, named by its table, and every blob it hides is named with the
// maps and tiles it holds; the other tables still read.
TEST(SqliteMapStoreTest, ADamagedTablePageIsNamedWithTheMapsItHits) {
  const std::string path = TempDir() + "/site.db";
  {
    auto dut = OpenOrDie(path);
    ASSERT_TRUE(dut);
    ASSERT_TRUE(dut->SaveMap(SampleSnapshot("corridor"), kCtx).ok());
  }
  // The first leaf page of the blobs table, found with the dbstat virtual table.
  int64_t page = 0, page_size = 0;
  {
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
    sqlite3_stmt* st = nullptr;
    ASSERT_EQ(sqlite3_prepare_v2(raw,
                                 "SELECT pageno, pgsize FROM dbstat WHERE name = 'blobs' AND "
                                 "pagetype = 'leaf' ORDER BY pageno LIMIT 1",
                                 -1, &st, nullptr),
              SQLITE_OK)
        << sqlite3_errmsg(raw);
    ASSERT_EQ(sqlite3_step(st), SQLITE_ROW);
    page = sqlite3_column_int64(st, 0);
    page_size = sqlite3_column_int64(st, 1);
    sqlite3_finalize(st);
    sqlite3_close(raw);
  }
  ASSERT_GT(page, 1);
  // Another program writes over the page's header (its page type byte and cell count).
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    ASSERT_TRUE(f.good());
    f.seekp((page - 1) * page_size);
    const char garbage[8] = {0x7f, 0x7f, 0x7f, 0x7f, 0x7f, 0x7f, 0x7f, 0x7f};
    f.write(garbage, sizeof(garbage));
  }
  auto dut = OpenOrDie(path, ReadOnly());
  ASSERT_TRUE(dut);
  auto report = dut->Check();
  ASSERT_TRUE(report.ok()) << report.status().ToString();
  EXPECT_FALSE(report->ok);
  std::string all;
  for (const std::string& p : report->problems) all += p + "\n";
  EXPECT_NE(all.find("integrity_check"), std::string::npos) << all;
  EXPECT_NE(all.find("table blobs"), std::string::npos) << all;
  EXPECT_NE(all.find("cannot be read"), std::string::npos) << all;
  EXPECT_NE(all.find("map lab/corridor v1 layer "), std::string::npos) << all;
  // The map's list entry still reads; its tiles are refused as corrupt, naming the file.
  EXPECT_TRUE(dut->GetMapInfo({"lab", "corridor", 0}).ok());
  auto map = dut->LoadLayers({"lab", "corridor", 0}, {});
  EXPECT_EQ(map.status().code(), StatusCode::kCorrupt) << map.status().ToString();
  EXPECT_NE(map.status().message().find("'" + path + "'"), std::string::npos)
      << map.status().message();
}

// SQLite's codes become statuses a caller can act on: a write the file refuses is not a bad
// request (kPermissionDenied, not kInvalidArgument), a full disk is kResourceExhausted.
TEST(SqliteMapStoreTest, SqliteCodesBecomeStatusesThatSayWhatWasWrong) {
  const std::string path = TempDir() + "/site.db";
  { ASSERT_TRUE(OpenOrDie(path)); }
  auto db = sqlite::Database::Open(path, /*read_only=*/true, /*create=*/false);
  ASSERT_TRUE(db.ok()) << db.status().ToString();
  const common::Status s = (*db)->Exec("INSERT INTO sites(name, created_utime) VALUES('x', 0)");
  EXPECT_EQ(s.code(), StatusCode::kPermissionDenied) << s.ToString();
  EXPECT_NE(s.message().find("readonly"), std::string::npos) << s.message();
  EXPECT_EQ(sqlite::StatusFromCode(SQLITE_FULL, "saving").code(), StatusCode::kResourceExhausted);
  EXPECT_EQ(sqlite::StatusFromCode(SQLITE_FULL, "saving").message(),
            "saving: database or disk is full");
  EXPECT_EQ(sqlite::StatusFromCode(SQLITE_CORRUPT, "x").code(), StatusCode::kCorrupt);
}

TEST(SqliteMapStoreTest, SynchronousIsNormalUnlessFullIsAskedFor) {
  const std::string path = TempDir() + "/site.db";
  {
    auto dut = OpenOrDie(path);
    ASSERT_TRUE(dut);
    EXPECT_EQ(dut->SynchronousLevel().value(), 1);  // NORMAL
  }
  SqliteOptions full;
  full.synchronous = Synchronous::kFull;
  auto dut = OpenOrDie(path, full);
  ASSERT_TRUE(dut);
  EXPECT_EQ(dut->SynchronousLevel().value(), 2);  // FULL
  ASSERT_TRUE(dut->SaveMap(SampleSnapshot("corridor"), kCtx).ok());
  EXPECT_EQ(ParseSynchronous("Full"), Synchronous::kFull);
  EXPECT_EQ(ParseSynchronous("normal"), Synchronous::kNormal);
  EXPECT_FALSE(ParseSynchronous("off").has_value());
  EXPECT_STREQ(SynchronousName(Synchronous::kFull), "full");
}

// A file this process may not write is served read-only: reads work, writes are refused naming
// the file and the reason. Root writes any file whatever its mode, so as root this needs a
// read-only mount (tests/integration/mapstore/mapstore_faults_test.cc does both).
TEST(SqliteMapStoreTest, AFileWithoutWriteAccessOpensReadOnlyAndSaysWhy) {
  if (geteuid() == 0) {
    GTEST_SKIP() << "running as root, which may write a file of mode 0444; the integration test "
                    "MapstoreFaultsTest.ReadOnlyFile covers it as user nobody";
  }
  const std::string dir = TempDir() + "/ro";
  fs::create_directories(dir);
  const std::string path = dir + "/site.db";
  {
    auto dut = OpenOrDie(path);
    ASSERT_TRUE(dut);
    ASSERT_TRUE(dut->SaveMap(SampleSnapshot("corridor"), kCtx).ok());
  }
  fs::permissions(path, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  fs::permissions(dir, fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                           fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec);
  const std::string before = ReadFile(path);
  {
    auto dut = OpenOrDie(path);
    ASSERT_TRUE(dut);
    EXPECT_NE(dut->write_refusal().find("Permission denied"), std::string::npos)
        << dut->write_refusal();
    EXPECT_TRUE(dut->LoadLayers({"lab", "corridor", 0}, {}).ok());
    auto r = dut->SaveMap(SampleSnapshot("corridor"), kCtx);
    EXPECT_EQ(r.status().code(), StatusCode::kPermissionDenied);
    EXPECT_NE(r.status().message().find("'" + path + "'"), std::string::npos);
  }
  EXPECT_TRUE(ReadFile(path) == before);
  fs::permissions(dir, fs::perms::owner_all);
}

TEST(SqliteMapStoreTest, CachedDerivedTilesAreTheStoredBlobsAndAreChecked) {
  const std::string path = TempDir() + "/site.db";
  const MapRef ref{"lab", "corridor", 1};
  {
    SqliteOptions small_tiles;
    small_tiles.tile_size_cells = 16;
    auto dut = OpenOrDie(path, small_tiles);
    const MapSnapshot s = SampleSnapshot("corridor");
    ASSERT_TRUE(dut->SaveMap(s, kCtx).ok());
    DerivedProfile d = testing::RoverDerivation(s.base.geometry());
    common::Layer& cost = d.layers.at("cost/rover");
    for (int64_t i = 0; i < cost.size(); ++i) cost.data()[i] = static_cast<float>(i % 97);
    ASSERT_TRUE(dut->PutDerived(ref, d, kCtx).ok());
    // The tiles are the stored rows themselves, not compressed again.
    auto hit = dut->FindDerivedTiles(ref, "h1", "c1", {"cost/rover"});
    ASSERT_TRUE(hit.ok() && hit->has_value()) << hit.status().ToString();
    ASSERT_EQ((*hit)->layers.size(), 1u);
    EXPECT_EQ((*hit)->layers[0].tile_size, 16);
    const StoredTile& first = (*hit)->layers[0].tiles.at(0);
    ASSERT_EQ(first.tile_ix, 0);
    ASSERT_EQ(first.tile_iy, 0);
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
    sqlite3_stmt* st = nullptr;
    ASSERT_EQ(sqlite3_prepare_v2(db,
                                 "SELECT b.data FROM derived_tiles t JOIN blobs b ON b.id = "
                                 "t.blob_id WHERE t.tile_ix = 0 AND t.tile_iy = 0",
                                 -1, &st, nullptr),
              SQLITE_OK);
    ASSERT_EQ(sqlite3_step(st), SQLITE_ROW);
    const std::string stored(static_cast<const char*>(sqlite3_column_blob(st, 0)),
                             static_cast<size_t>(sqlite3_column_bytes(st, 0)));
    sqlite3_finalize(st);
    sqlite3_close(db);
    EXPECT_EQ(first.data, stored);
  }
  // Another program damages one cached tile: it is refused, naming it.
  RawExec(path,
          "DROP TRIGGER blobs_immutable;"
          "UPDATE blobs SET data = substr(data, 1, 20) || CASE WHEN substr(data, 21, 1) = X'00' "
          "THEN X'01' ELSE X'00' END || substr(data, 22) WHERE id = (SELECT blob_id FROM "
          "derived_tiles WHERE tile_ix = 1 AND tile_iy = 0);");
  auto dut = OpenOrDie(path);
  auto damaged = dut->FindDerivedTiles(ref, "h1", "c1", {"cost/rover"});
  EXPECT_EQ(damaged.status().code(), StatusCode::kCorrupt);
  EXPECT_NE(damaged.status().message().find("tile (1, 0)"), std::string::npos)
      << damaged.status().message();
  EXPECT_NE(damaged.status().message().find("cost/rover"), std::string::npos)
      << damaged.status().message();
}

// A pushed save's tiles arrive compressed: the store keeps those bytes for a tile that is one
// of its own and whose CRC is that of the saved cells, and compresses the others itself.
TEST(SqliteMapStoreTest, SaveKeepsTheCallersCompressedTilesThatMatchTheCells) {
  SqliteOptions small_tiles;
  small_tiles.tile_size_cells = 16;
  auto dut = OpenOrDie(TempDir() + "/site.db", small_tiles);
  MapSnapshot s = SampleSnapshot("corridor");  // 37 x 23 cells: tiles 3 x 2
  const common::Layer& elevation = s.base.at(layers::kElevation);
  auto encode = [&](const common::Layer& cells_of, int ix, int iy) {
    const TileSpec spec = TilesOf(s.base.geometry(), 16)[static_cast<size_t>(iy * 3 + ix)];
    const std::vector<float> cells = ExtractTile(cells_of, spec);
    // Another compression level than the store's: the bytes show whose they are.
    EncodedBlob blob = EncodeBlob(cells.data(), cells.size() * sizeof(float), Codec::kZstdShuffle4,
                                  /*zstd_level=*/9);
    return StoredTile{ix,
                      iy,
                      spec.cells_x,
                      spec.cells_y,
                      static_cast<int>(blob.codec),
                      blob.raw_crc32,
                      blob.data,
                      blob.stored_crc32};
  };
  common::Layer other = elevation;
  other.array() += 1.f;
  StoredLayer pushed;
  pushed.name = layers::kElevation;
  pushed.tile_size = 16;
  pushed.tiles = {encode(elevation, 1, 0), encode(other, 2, 1)};  // the second is not the cells'
  s.encoded_layers = {pushed};
  ASSERT_TRUE(dut->SaveMap(s, kCtx).ok());

  auto bytes = dut->BaseBlobBytes({"lab", "corridor", 1});
  ASSERT_TRUE(bytes.ok()) << bytes.status().ToString();
  EXPECT_EQ(bytes->at("elevation/1/0"), pushed.tiles[0].data) << "the pushed bytes are kept";
  EXPECT_NE(bytes->at("elevation/2/1"), pushed.tiles[1].data) << "a tile of other cells is not";
  auto loaded = dut->LoadLayers({"lab", "corridor", 1}, {});
  ASSERT_TRUE(loaded.ok()) << loaded.status().ToString();
  EXPECT_TRUE(SameLayer(loaded->at(layers::kElevation), elevation));
  EXPECT_TRUE(dut->Check().value().ok);

  // Tiles of another size are no tiles of the store: all compressed again (in a fresh file, as
  // a blob of the same content is stored once).
  auto fresh = OpenOrDie(TempDir() + "/other.db", small_tiles);
  pushed.tile_size = 8;
  s.encoded_layers = {pushed};
  ASSERT_TRUE(fresh->SaveMap(s, kCtx).ok());
  auto again = fresh->BaseBlobBytes({"lab", "corridor", 1});
  ASSERT_TRUE(again.ok());
  EXPECT_NE(again->at("elevation/1/0"), pushed.tiles[0].data);
  EXPECT_TRUE(
      SameLayer(fresh->LoadLayers({"lab", "corridor", 1}, {})->at(layers::kElevation), elevation));

  // A caller that checked its tiles (the service, which decoded each on receipt) has them
  // adopted without the store reading the cells: even the tile of other cells is kept, and
  // the map loads as those tiles say.
  auto checked = OpenOrDie(TempDir() + "/checked.db", small_tiles);
  pushed.tile_size = 16;
  s.encoded_layers = {pushed};
  s.encoded_layers_checked = true;
  ASSERT_TRUE(checked->SaveMap(s, kCtx).ok());
  auto kept = checked->BaseBlobBytes({"lab", "corridor", 1});
  ASSERT_TRUE(kept.ok());
  EXPECT_EQ(kept->at("elevation/1/0"), pushed.tiles[0].data);
  EXPECT_EQ(kept->at("elevation/2/1"), pushed.tiles[1].data);
  auto as_pushed = checked->LoadLayers({"lab", "corridor", 1}, {});
  ASSERT_TRUE(as_pushed.ok());
  EXPECT_FLOAT_EQ(as_pushed->at(layers::kElevation)(36, 22), other(36, 22));
  EXPECT_FLOAT_EQ(as_pushed->at(layers::kElevation)(20, 5), elevation(20, 5));
  EXPECT_TRUE(checked->Check().value().ok);
}

TEST(SqliteMapStoreTest, StoredBlobsAndVersionsCannotBeRewritten) {
  const std::string path = TempDir() + "/site.db";
  auto dut = OpenOrDie(path);
  ASSERT_TRUE(dut->SaveMap(SampleSnapshot("corridor"), kCtx).ok());
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
  char* error = nullptr;
  EXPECT_NE(sqlite3_exec(raw, "UPDATE blobs SET data = X'00'", nullptr, nullptr, &error),
            SQLITE_OK);
  EXPECT_NE(std::string(error ? error : "").find("immutable"), std::string::npos);
  sqlite3_free(error);
  EXPECT_NE(sqlite3_exec(raw, "UPDATE map_versions SET size_x = 1", nullptr, nullptr, nullptr),
            SQLITE_OK);
  EXPECT_NE(sqlite3_exec(raw, "DELETE FROM layer_tiles", nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(raw);
  EXPECT_TRUE(dut->Check().value().ok);
}

TEST(SqliteMapStoreTest, IdenticalTilesAreStoredOnce) {
  const std::string path = TempDir() + "/site.db";
  auto dut = OpenOrDie(path);
  MapSnapshot s = SampleSnapshot("corridor", 300, 200);
  ASSERT_TRUE(dut->SaveMap(s, kCtx).ok());
  const auto blobs_v1 = dut->BaseBlobBytes({"lab", "corridor", 1});
  ASSERT_TRUE(blobs_v1.ok());
  // Change one cell: one tile more, not a whole map.
  s.base.at("elevation")(150, 150) = 42.f;
  ASSERT_TRUE(dut->SaveMap(s, kCtx).ok());
  const auto blobs_v2 = dut->BaseBlobBytes({"lab", "corridor", 2});
  ASSERT_TRUE(blobs_v2.ok());
  int differing = 0;
  for (const auto& [key, bytes] : *blobs_v2) differing += blobs_v1->at(key) != bytes;
  EXPECT_EQ(differing, 1);
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(raw, "SELECT count(*) FROM blobs", -1, &st, nullptr);
  ASSERT_EQ(sqlite3_step(st), SQLITE_ROW);
  EXPECT_EQ(sqlite3_column_int(st, 0), static_cast<int>(blobs_v1->size()) + 1);
  sqlite3_finalize(st);
  sqlite3_close(raw);
}

TEST(SqliteMapStoreTest, ReadOnlyUseLeavesTheFileUntouched) {
  const std::string path = TempDir() + "/site.db";
  const ProfileDeriver deriver = FakeDeriver();
  {
    auto dut = OpenOrDie(path);
    ASSERT_TRUE(dut->SaveMap(SampleSnapshot("corridor"), kCtx).ok());
    ASSERT_TRUE(dut->PutProfile(Profile("rover", 12.0, 0.08), kCtx).ok());
    ASSERT_TRUE(dut->PutProfile(Profile("pioneer3at", 8.0, 0.03), kCtx).ok());
    ASSERT_TRUE(dut->PutPlaces("lab", {{"hall", {{0, 0}, {1, 0}, {1, 1}}}}, kCtx).ok());
    ASSERT_TRUE(ShareMap(*dut, deriver, {"lab", "corridor", 0}, "rover", kCtx).ok());
  }
  const std::string bytes_before = ReadFile(path);
  struct stat before {};
  ASSERT_EQ(stat(path.c_str(), &before), 0);
  for (bool read_only : {true, false}) {
    SqliteOptions options;
    options.read_only = read_only;
    auto dut = OpenOrDie(path, options);
    ASSERT_TRUE(dut);
    ASSERT_TRUE(dut->ListMaps({}).ok());
    ASSERT_TRUE(dut->ListProfiles().ok());
    ASSERT_TRUE(dut->ListPlaces("lab").ok());
    ASSERT_TRUE(dut->ListAudit(10).ok());
    ASSERT_TRUE(LoadForProfile(*dut, &deriver, {"lab", "corridor", 0}, "rover").ok());
    ASSERT_TRUE(LoadForProfile(*dut, &deriver, {"lab", "corridor", 0}, "pioneer3at").ok());
    ASSERT_TRUE(dut->LoadOctomap({"lab", "corridor", 0}).status().code() == StatusCode::kNotFound);
    ASSERT_TRUE(dut->Check().value().ok);
  }
  struct stat after {};
  ASSERT_EQ(stat(path.c_str(), &after), 0);
  EXPECT_EQ(after.st_mtim.tv_sec, before.st_mtim.tv_sec);
  EXPECT_EQ(after.st_mtim.tv_nsec, before.st_mtim.tv_nsec);
  EXPECT_TRUE(ReadFile(path) == bytes_before);
  // A read-only store refuses writes with a message.
  auto ro = OpenOrDie(path, ReadOnly());
  const common::Status s = ro->PutProfile(Profile("tank", 5.0, 0.01), kCtx);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("read-only"), std::string::npos);
}

TEST(SqliteMapStoreTest, FullDiskGivesAClearErrorAndLosesNothing) {
  const std::string path = TempDir() + "/site.db";
  int64_t pages = 0;
  {
    auto dut = OpenOrDie(path);
    ASSERT_TRUE(dut->SaveMap(SampleSnapshot("corridor"), kCtx).ok());
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
    sqlite3_stmt* st = nullptr;
    sqlite3_prepare_v2(raw, "PRAGMA page_count", -1, &st, nullptr);
    ASSERT_EQ(sqlite3_step(st), SQLITE_ROW);
    pages = sqlite3_column_int64(st, 0);
    sqlite3_finalize(st);
    sqlite3_close(raw);
  }
  // A quota a few pages above the current size stands in for a full disk (same SQLITE_FULL).
  SqliteOptions options;
  options.max_page_count = pages + 3;
  auto dut = OpenOrDie(path, options);
  ASSERT_TRUE(dut);
  MapSnapshot big = SampleSnapshot("big", 400, 400);
  for (int iy = 0; iy < 400; ++iy) {
    for (int ix = 0; ix < 400; ++ix) big.base.at("elevation")(ix, iy) = std::sin(ix * 0.37f + iy);
  }
  auto r = dut->SaveMap(big, kCtx);
  ASSERT_EQ(r.status().code(), StatusCode::kResourceExhausted) << r.status().ToString();
  EXPECT_NE(r.status().message().find("disk full"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("'" + path + "'"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("quota of"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("intact"), std::string::npos);
  // Nothing of the failed save exists; the earlier map loads and the file checks clean.
  EXPECT_EQ(dut->GetMapInfo({"lab", "big", 0}).status().code(), StatusCode::kNotFound);
  auto old = dut->LoadLayers({"lab", "corridor", 0}, {});
  ASSERT_TRUE(old.ok()) << old.status().ToString();
  EXPECT_FLOAT_EQ(old->at("elevation")(20, 1), 0.501f);
  EXPECT_TRUE(dut->Check().value().ok);
  // With room again (a larger quota) the same save succeeds on the same file.
  dut.reset();
  options.max_page_count = 0;
  dut = OpenOrDie(path, options);
  ASSERT_TRUE(dut);
  auto again = dut->SaveMap(big, kCtx);
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  EXPECT_EQ(again->version, 1);
  EXPECT_TRUE(dut->Check().value().ok);
}

TEST(SqliteMapStoreTest, TwoWritersAndAReaderOnOneFileAllSucceed) {
  const std::string path = TempDir() + "/site.db";
  { ASSERT_TRUE(OpenOrDie(path)); }
  constexpr int kSaves = 12;
  std::atomic<int> failures{0};
  std::atomic<bool> writing{true};
  std::atomic<int> reads{0};
  auto writer = [&](const std::string& name) {
    auto dut = OpenOrDie(path);
    if (!dut) {
      ++failures;
      return;
    }
    for (int i = 0; i < kSaves; ++i) {
      auto r = dut->SaveMap(SampleSnapshot(name, 120, 90, static_cast<float>(i)), kCtx);
      if (!r.ok()) {
        ADD_FAILURE() << r.status().ToString();
        ++failures;
      }
    }
  };
  std::thread reader([&] {
    auto dut = OpenOrDie(path, ReadOnly());
    while (writing) {
      auto list = dut->ListMaps({"", "", true, false});
      if (!list.ok()) {
        ADD_FAILURE() << list.status().ToString();
        ++failures;
      }
      for (const MapInfo& info : list.value()) {
        auto map = dut->LoadLayers({info.site, info.name, info.version}, {});
        if (!map.ok()) {
          ADD_FAILURE() << map.status().ToString();
          ++failures;
        }
      }
      ++reads;
    }
  });
  std::thread a(writer, "north");
  std::thread b(writer, "south");
  a.join();
  b.join();
  writing = false;
  reader.join();
  EXPECT_EQ(failures, 0);
  EXPECT_GT(reads, 0);
  auto dut = OpenOrDie(path);
  for (const std::string name : {"north", "south"}) {
    auto versions = dut->ListMaps({"lab", name, true, true});
    ASSERT_TRUE(versions.ok());
    ASSERT_EQ(static_cast<int>(versions->size()), kSaves) << name;
    for (int i = 0; i < kSaves; ++i) {
      EXPECT_EQ((*versions)[i].version, i + 1);
      auto map = dut->LoadLayers({"lab", name, i + 1}, {{"elevation"}, std::nullopt});
      ASSERT_TRUE(map.ok());
      EXPECT_FLOAT_EQ(map->at("elevation")(5, 5), static_cast<float>(i) + 0.005f);
    }
  }
  EXPECT_TRUE(dut->Check().value().ok);
}

TEST(SqliteMapStoreTest, ThreeOpenersOfANewFileAllGetTheSchema) {
  // Services started together on one new file: one creates the schema while the others read
  // its header; none may see half of it (tables but no application id) and refuse the file.
  const std::string dir = TempDir();
  constexpr int kRounds = 40;
  constexpr int kOpeners = 3;
  for (int round = 0; round < kRounds; ++round) {
    const std::string path = dir + "/site" + std::to_string(round) + ".db";
    std::atomic<int> waiting{kOpeners};
    std::vector<std::string> errors(kOpeners);
    std::vector<std::thread> openers;
    for (int k = 0; k < kOpeners; ++k) {
      openers.emplace_back([&, k] {
        --waiting;
        while (waiting > 0) std::this_thread::yield();  // start together
        auto store = SqliteMapStore::Open(path, {});
        if (!store.ok()) errors[k] = store.status().ToString();
      });
    }
    for (auto& t : openers) t.join();
    for (int k = 0; k < kOpeners; ++k) {
      EXPECT_EQ(errors[k], "") << "round " << round << ", opener " << k;
    }
    auto dut = OpenOrDie(path, ReadOnly());
    ASSERT_TRUE(dut);
    EXPECT_TRUE(dut->Check().value().ok);
  }
}

TEST(SqliteMapStoreTest, VacuumKeepsEverythingReferenced) {
  const std::string path = TempDir() + "/site.db";
  auto dut = OpenOrDie(path);
  ASSERT_TRUE(dut->SaveMap(SampleSnapshot("corridor", 200, 200), kCtx).ok());
  ASSERT_TRUE(dut->SaveMap(SampleSnapshot("corridor", 200, 200, 1.f), kCtx).ok());
  ASSERT_TRUE(dut->DeleteMap({"lab", "corridor", 1}, kCtx).ok());
  const auto before = dut->BaseBlobBytes({"lab", "corridor", 2});
  auto shrunk = dut->Vacuum();
  ASSERT_TRUE(shrunk.ok()) << shrunk.status().ToString();
  EXPECT_TRUE(dut->Check().value().ok);
  EXPECT_EQ(dut->BaseBlobBytes({"lab", "corridor", 2}).value(), before.value());
  // Soft-deleted versions keep their data.
  auto listed = dut->ListMaps({"lab", "corridor", true, true});
  ASSERT_EQ(listed->size(), 2u);
}

TEST(SqliteMapStoreTest, OpeningTheVersion1FixtureMigratesIt) {
  const std::string path = TempDir() + "/v1.db";
  fs::copy_file(std::string(CAIRN_SOURCE_DIR) + "/tests/unit/mapstore/fixtures/v1.db", path);

  // Read-only cannot migrate: a message says what to do.
  auto ro = SqliteMapStore::Open(path, ReadOnly());
  EXPECT_EQ(ro.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(ro.status().message().find("schema version 1"), std::string::npos);
  EXPECT_NE(ro.status().message().find("migrate"), std::string::npos);

  auto dut = OpenOrDie(path);
  ASSERT_TRUE(dut);
  EXPECT_EQ(dut->schema_version(), schema::kCurrentVersion);
  auto info = dut->GetMapInfo({"lab", "corridor", 0});
  ASSERT_TRUE(info.ok()) << info.status().ToString();
  EXPECT_EQ(info->version, 1);  // version 2 was deleted in the fixture
  EXPECT_EQ(info->provenance.source_robot, "rover1");
  EXPECT_EQ(info->provenance.source_profile, "pioneer3at");
  EXPECT_EQ(info->provenance.created_utime, 1700000001000000);
  EXPECT_EQ(info->geometry.size_x, 25);
  EXPECT_EQ(info->geometry.size_y, 12);
  EXPECT_DOUBLE_EQ(info->geometry.resolution_m, 0.2);
  EXPECT_DOUBLE_EQ(info->geometry.origin.x_m, -1.0);
  EXPECT_EQ(info->tile_size, 10);
  EXPECT_EQ(info->layers, (std::vector<std::string>{"elevation", "static"}));
  EXPECT_EQ(info->num_obstacles, 2);

  auto map = dut->LoadLayers({"lab", "corridor", 1}, {});
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  for (int iy = 0; iy < 12; ++iy) {
    for (int ix = 0; ix < 25; ++ix) {
      const float e = map->at("elevation")(ix, iy);
      if ((ix == 0 && iy == 0) || (ix >= 20 && iy >= 10)) {
        EXPECT_TRUE(std::isnan(e)) << ix << "," << iy;
      } else {
        EXPECT_FLOAT_EQ(e, 0.01f * ix + 0.02f * iy) << ix << "," << iy;
      }
      EXPECT_EQ(map->at("static")(ix, iy), ix == 12 ? 100.f : 0.f);
    }
  }
  auto deleted = dut->GetMapInfo({"lab", "corridor", 2});
  EXPECT_EQ(deleted.status().code(), StatusCode::kNotFound);
  auto yard = dut->LoadLayers({"lab", "yard", 0}, {});
  ASSERT_TRUE(yard.ok());
  EXPECT_FLOAT_EQ(yard->at("elevation")(4, 4), 0.25f);
  EXPECT_DOUBLE_EQ(yard->geometry().origin.yaw_rad, 0.5);

  auto obstacles = dut->LoadObstacles({"lab", "corridor", 0});
  ASSERT_TRUE(obstacles.ok());
  ASSERT_EQ(obstacles->obstacles.size(), 2u);
  EXPECT_EQ(obstacles->obstacles[0].kind, common::ObstacleKind::kRamp);
  EXPECT_NEAR(obstacles->obstacles[0].slope_rad, 10.0 * M_PI / 180.0, 1e-12);
  EXPECT_TRUE(std::isnan(obstacles->obstacles[0].depth_m));
  EXPECT_EQ(obstacles->obstacles[1].kind, common::ObstacleKind::kStepUp);
  EXPECT_DOUBLE_EQ(obstacles->obstacles[1].height_m, 0.05);

  // The profile is re-hashed with today's code so new puts of the same content match it.
  auto profile = dut->GetProfile("pioneer3at");
  ASSERT_TRUE(profile.ok()) << profile.status().ToString();
  const common::RobotProfile shipped = common::LoadRobotProfileFile(
      std::string(CAIRN_SOURCE_DIR) + "/config/profiles/pioneer3at.yaml");
  EXPECT_EQ(profile->content_hash, shipped.ContentHash());
  EXPECT_EQ(profile->profile, shipped);

  auto audit = dut->ListAudit(5);
  ASSERT_TRUE(audit.ok());
  ASSERT_FALSE(audit->empty());
  EXPECT_EQ((*audit)[0].op, "migrate");
  EXPECT_TRUE(dut->Check().value().ok);
  // New saves continue the numbering of the migrated map.
  MapSnapshot next = SampleSnapshot("corridor", 25, 12);
  auto saved = dut->SaveMap(next, kCtx);
  ASSERT_TRUE(saved.ok());
  EXPECT_EQ(saved->version, 3);
  // Reopening does not migrate twice.
  dut.reset();
  auto again = OpenOrDie(path);
  EXPECT_EQ(again->ListAudit(10).value()[0].op, "save");
}

// Every blob row's (codec, raw_size, raw_crc32, data, stored_crc32), read through a raw
// connection.
struct BlobRow {
  int codec;
  int64_t raw_size;
  uint32_t raw_crc32;
  std::string data;
  std::optional<uint32_t> stored_crc32;
};
std::vector<BlobRow> RawBlobs(const std::string& path) {
  std::vector<BlobRow> rows;
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(db,
                               "SELECT codec, raw_size, raw_crc32, data, stored_crc32 FROM blobs "
                               "ORDER BY id",
                               -1, &st, nullptr),
            SQLITE_OK);
  while (st != nullptr && sqlite3_step(st) == SQLITE_ROW) {
    BlobRow r;
    r.codec = sqlite3_column_int(st, 0);
    r.raw_size = sqlite3_column_int64(st, 1);
    r.raw_crc32 = static_cast<uint32_t>(sqlite3_column_int64(st, 2));
    r.data.assign(static_cast<const char*>(sqlite3_column_blob(st, 3)),
                  static_cast<size_t>(sqlite3_column_bytes(st, 3)));
    if (sqlite3_column_type(st, 4) != SQLITE_NULL)
      r.stored_crc32 = static_cast<uint32_t>(sqlite3_column_int64(st, 4));
    rows.push_back(std::move(r));
  }
  sqlite3_finalize(st);
  sqlite3_close(db);
  return rows;
}

// v2.db was written by SqliteMapStore at schema version 2 (see fixtures/README.md): corridor
// version 1 is SampleSnapshot("corridor", 25, 12) plus a layer "static" (100 in column 12, 0
// elsewhere), version 2 is deleted, profile "rover" has a cached derivation (hash "h1", code
// "c1") whose cost/rover cell i (x fastest) is i % 97, and the site has a place "kitchen".
TEST(SqliteMapStoreTest, OpeningTheVersion2FixtureMigratesIt) {
  const std::string path = TempDir() + "/v2.db";
  fs::copy_file(std::string(CAIRN_SOURCE_DIR) + "/tests/unit/mapstore/fixtures/v2.db", path);
  {  // schema 2 has no stored_crc32 column
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
    sqlite3_stmt* st = nullptr;
    EXPECT_NE(sqlite3_prepare_v2(db, "SELECT stored_crc32 FROM blobs", -1, &st, nullptr),
              SQLITE_OK);
    sqlite3_finalize(st);
    sqlite3_close(db);
  }

  auto ro = SqliteMapStore::Open(path, ReadOnly());
  EXPECT_EQ(ro.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(ro.status().message().find("schema version 2"), std::string::npos);
  EXPECT_NE(ro.status().message().find("migrate"), std::string::npos);

  auto dut = OpenOrDie(path);
  ASSERT_TRUE(dut);
  EXPECT_EQ(dut->schema_version(), schema::kCurrentVersion);
  // Every blob now records the checksum of its stored bytes and header.
  const std::vector<BlobRow> blobs = RawBlobs(path);
  EXPECT_EQ(blobs.size(), 31u);
  for (const BlobRow& b : blobs) {
    ASSERT_TRUE(b.stored_crc32.has_value());
    EXPECT_EQ(*b.stored_crc32,
              StoredBlobCrc32(b.codec, b.raw_size, b.raw_crc32, b.data.data(), b.data.size()));
  }

  const MapSnapshot expected = SampleSnapshot("corridor", 25, 12);
  auto info = dut->GetMapInfo({"lab", "corridor", 0});
  ASSERT_TRUE(info.ok()) << info.status().ToString();
  EXPECT_EQ(info->version, 1);
  EXPECT_EQ(info->provenance.source_robot, "rover1");
  EXPECT_EQ(info->tile_size, 10);
  EXPECT_EQ(info->num_obstacles, 2);
  EXPECT_EQ(dut->GetMapInfo({"lab", "corridor", 2}).status().code(), StatusCode::kNotFound);
  auto map = dut->LoadLayers({"lab", "corridor", 1}, {});
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  EXPECT_TRUE(SameLayer(map->at(layers::kElevation), expected.base.at(layers::kElevation)));
  EXPECT_TRUE(
      SameLayer(map->at(layers::kObservationCount), expected.base.at(layers::kObservationCount)));
  for (int iy = 0; iy < 12; ++iy) {
    for (int ix = 0; ix < 25; ++ix) EXPECT_EQ(map->at("static")(ix, iy), ix == 12 ? 100.f : 0.f);
  }
  auto obstacles = dut->LoadObstacles({"lab", "corridor", 1});
  ASSERT_TRUE(obstacles.ok());
  ASSERT_EQ(obstacles->obstacles.size(), 2u);
  for (const common::Obstacle& want : expected.obstacles.obstacles) {
    auto it = std::find_if(obstacles->obstacles.begin(), obstacles->obstacles.end(),
                           [&](const common::Obstacle& o) { return o.id == want.id; });
    ASSERT_NE(it, obstacles->obstacles.end()) << want.id;
    const common::Obstacle& got = *it;
    EXPECT_EQ(got.id, want.id);
    EXPECT_EQ(got.kind, want.kind);
    EXPECT_EQ(got.outline_m, want.outline_m);
    EXPECT_DOUBLE_EQ(got.slope_rad, want.slope_rad);
    EXPECT_DOUBLE_EQ(got.height_m, want.height_m);
    EXPECT_EQ(got.verdicts.size(), want.verdicts.size());
  }

  const common::RobotProfile rover = Profile("rover", 12.0, 0.08);
  auto profile = dut->GetProfile("rover");
  ASSERT_TRUE(profile.ok()) << profile.status().ToString();
  EXPECT_EQ(profile->profile, rover);
  EXPECT_EQ(profile->content_hash, rover.ContentHash());
  auto places = dut->ListPlaces("lab");
  ASSERT_TRUE(places.ok());
  EXPECT_EQ(*places, (std::vector<Place>{{"kitchen", {{0, 0}, {2, 0}, {2, 1}}}}));

  auto derived = dut->FindDerived({"lab", "corridor", 1}, "h1", "c1", {});
  ASSERT_TRUE(derived.ok() && derived->has_value()) << derived.status().ToString();
  const common::Layer& cost = (*derived)->layers.at("cost/rover");
  for (int i = 0; i < 25 * 12; ++i) EXPECT_EQ(cost(i % 25, i / 25), static_cast<float>(i % 97));
  auto tiles = dut->FindDerivedTiles({"lab", "corridor", 1}, "h1", "c1", {});
  ASSERT_TRUE(tiles.ok() && tiles->has_value()) << tiles.status().ToString();
  ASSERT_EQ((*tiles)->layers.size(), 1u);
  EXPECT_EQ((*tiles)->layers[0].tiles.size(), 6u);
  for (const StoredTile& t : (*tiles)->layers[0].tiles) EXPECT_TRUE(t.stored_crc32.has_value());

  EXPECT_TRUE(dut->Check().value().ok);
  auto audit = dut->ListAudit(1);
  ASSERT_TRUE(audit.ok() && !audit->empty());
  EXPECT_EQ((*audit)[0].op, "migrate");
  EXPECT_EQ((*audit)[0].detail, "schema 3 -> 4");
  auto steps = dut->ListAudit(2);
  ASSERT_TRUE(steps.ok() && steps->size() == 2u);
  EXPECT_EQ((*steps)[1].detail, "schema 2 -> 3");
  dut.reset();

  // A blob whose bytes change after the migration is refused where it is read, without
  // decompressing (the recorded stored_crc32 no longer matches), and by check.
  RawExec(path,
          "DROP TRIGGER blobs_immutable; UPDATE blobs SET data = data || x'00' WHERE id = "
          "(SELECT blob_id FROM derived_tiles LIMIT 1);");
  auto reopened = OpenOrDie(path);
  ASSERT_TRUE(reopened);
  auto refused = reopened->FindDerivedTiles({"lab", "corridor", 1}, "h1", "c1", {});
  EXPECT_EQ(refused.status().code(), StatusCode::kCorrupt);
  EXPECT_NE(refused.status().message().find("checksum"), std::string::npos)
      << refused.status().message();
  EXPECT_FALSE(reopened->Check().value().ok);
}

}  // namespace
}  // namespace cairn::mapstore
