// Store faults under real processes and real files: a read-only database (a file of mode 0444 in
// a folder of mode 0555 served as user nobody, and a read-only bind mount), a disk that fills up
// during a save (a small tmpfs), and a page of one map's blob damaged while the service runs.
//
// The mount tests need root and a private mount namespace (unshare(CLONE_NEWNS) before the test
// starts any thread; ctest runs every test in its own process). Where that is not possible they
// are skipped, saying why. Nothing mounted here is seen outside the test's namespace, and the
// mounts are undone at the end of the test.

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sched.h>
#include <sqlite3.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <unistd.h>

#include "mapstore/sqlite_map_store.h"
#include "tests/integration/mapstore/mapstore_fixture.h"

namespace cairn::mapstore::testing {
namespace {

namespace fs = std::filesystem;
constexpr int8_t kStatusCorrupt = Reply::STATUS_CORRUPT;
constexpr int8_t kStatusError = Reply::STATUS_ERROR;
constexpr int8_t kStatusForbidden = Reply::STATUS_FORBIDDEN;

// Moves this test process (and the processes it starts) into a mount namespace of its own
// whose mounts do not propagate back. Must run before any thread starts. "" on success, else
// why not.
std::string EnterPrivateMountNamespace() {
  if (geteuid() != 0) return "not root: mounting needs CAP_SYS_ADMIN";
  if (unshare(CLONE_NEWNS) != 0) {
    return std::string("unshare(CLONE_NEWNS) failed: ") + std::strerror(errno) +
           (errno == EINVAL ? " (the process already has threads: run the test alone, as ctest "
                              "does)"
                            : "");
  }
  if (mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) {
    return std::string("making / private failed: ") + std::strerror(errno);
  }
  return "";
}

// Unmounts (lazily) when the test ends, whatever happened.
struct MountGuard {
  std::string dir;
  ~MountGuard() {
    if (!dir.empty()) umount2(dir.c_str(), MNT_DETACH);
  }
};

// Two maps saved straight into a file (as an earlier run of the service left them); the store
// is closed, so the WAL is folded into the file and removed.
void MakeDatabase(const std::string& db) {
  auto store = SqliteMapStore::Open(db);
  ASSERT_TRUE(store.ok()) << store.status().ToString();
  for (const auto& [name, offset] : std::map<std::string, float>{{"north", 1.f}, {"south", 2.f}}) {
    auto saved = (*store)->SaveMap(TerrainSnapshot("lab", name, 260, 240, offset), {"test", 0, 0});
    ASSERT_TRUE(saved.ok()) << saved.status().ToString();
  }
}

// Loads a map through the service and compares its elevation with the snapshot it came from.
void ExpectLoads(MapstoreClient& client, const std::string& name, int64_t version,
                 const MapSnapshot& from) {
  auto loaded = client.Load("lab", name, version, "", {"elevation"});
  ASSERT_TRUE(loaded.ok()) << name << ": " << loaded.status().ToString();
  EXPECT_TRUE(SameLayer(loaded->layers.at("elevation"), from.base.at("elevation"))) << name;
}

// A map whose cells compress badly (a hash of the cell), so its save needs about as many bytes
// on disk as its cells take: 2 layers of 500 x 500 floats, 2 MB.
MapSnapshot NoisySnapshot(const std::string& name) {
  MapSnapshot s = TerrainSnapshot("lab", name, 500, 500, 0.f);
  for (const char* layer : {layers::kElevation, layers::kElevationVariance}) {
    auto& cells = s.base.at(layer);
    uint32_t h = 2166136261u;
    for (int iy = 0; iy < 500; ++iy) {
      for (int ix = 0; ix < 500; ++ix) {
        h = (h ^ static_cast<uint32_t>(ix * 7919 + iy)) * 16777619u;
        cells(ix, iy) = static_cast<float>(h % 1000003u) * 1e-5f;
      }
    }
  }
  return s;
}

bool LogHas(const ChildProcess& p, const std::string& text) {
  return WaitFor([&] { return p.Log().find(text) != std::string::npos; }, 5.0);
}

// The checks shared by both read-only cases: loads work, a save and a profile put are refused
// naming the file and the reason, the refusal is logged, the service keeps answering, and the
// file is untouched.
void ExpectServedReadOnly(ChildProcess& store, const std::string& url, const std::string& db,
                          const std::string& reason) {
  lcm::LCM lcm(url);
  MapstoreClient client(lcm, "read-only-test", TestClientOptions());
  ASSERT_TRUE(WaitForStore(client)) << "the service did not start on a read-only database";
  const std::string before = ReadAll(db);
  EXPECT_TRUE(LogHas(store, "serving read-only, saves will fail: '" + db + "'")) << store.Log();
  ExpectLoads(client, "north", 1, TerrainSnapshot("lab", "north", 260, 240, 1.f));

  auto saved = client.Save(TerrainSnapshot("lab", "north", 260, 240, 3.f));
  ASSERT_TRUE(saved.ok()) << saved.status().ToString();
  EXPECT_EQ(saved->status, kStatusForbidden) << saved->message;
  for (const std::string& part :
       {"'" + db + "'", std::string("read-only"), reason, std::string("nothing was written")}) {
    EXPECT_NE(saved->message.find(part), std::string::npos) << part << " in: " << saved->message;
  }
  std::printf("[ info ] save refused: %s\n", saved->message.c_str());
  EXPECT_TRUE(LogHas(store, "save of lab/north failed: PERMISSION_DENIED")) << store.Log();
  auto put = client.Call(PutProfileRequest(ShippedProfile("kobuki")));
  ASSERT_TRUE(put.ok());
  EXPECT_EQ(put->status, kStatusForbidden) << put->message;

  // Still serving: the other map loads, the list is what it was.
  EXPECT_TRUE(store.Running());
  ExpectLoads(client, "south", 1, TerrainSnapshot("lab", "south", 260, 240, 2.f));
  auto list = client.Call(MakeRequest(Request::OP_LIST_MAPS, "lab", "north"));
  ASSERT_TRUE(list.ok());
  EXPECT_EQ(list->num_maps, 1);
  EXPECT_TRUE(ReadAll(db) == before) << "the read-only file changed";
  EXPECT_FALSE(fs::exists(db + "-wal"));
}

TEST(MapstoreFaultsTest, ReadOnlyFileIsServedAndSavesFailSayingWhy) {
  // Root writes a file whatever its mode, so as root the service runs as user nobody.
  std::vector<std::string> as_user;
  if (geteuid() == 0) {
    if (access("/usr/bin/setpriv", X_OK) != 0) {
      GTEST_SKIP() << "running as root without setpriv (util-linux): cannot run the service as "
                      "a user that mode 0444 stops";
    }
    as_user = {"/usr/bin/setpriv", "--reuid=nobody", "--regid=nogroup", "--clear-groups"};
  }
  ProcessSet procs(cairn::testing::PrivateLcmUrl());
  // User nobody must reach the file: every folder above it must be searchable by others.
  for (fs::path p = fs::path(procs.dir()); p != p.root_path(); p = p.parent_path()) {
    if ((fs::status(p).permissions() & fs::perms::others_exec) == fs::perms::none) {
      GTEST_SKIP() << p
                   << " is not searchable by other users, so user nobody cannot reach the "
                      "test's database";
    }
  }
  const std::string dir = procs.dir() + "/ro";
  fs::create_directories(dir);
  const std::string db = dir + "/site.db";
  MakeDatabase(db);
  ASSERT_EQ(chmod(db.c_str(), 0444), 0);
  ASSERT_EQ(chmod(dir.c_str(), 0555), 0);
  std::vector<std::string> argv = as_user;
  for (const std::string& a : {BinPath("cairn-mapstore"), std::string("--db"), db,
                               std::string("--lcm-url"), procs.url()}) {
    argv.push_back(a);
  }
  ChildProcess& store = procs.StartRaw("cairn-mapstore", argv);
  ExpectServedReadOnly(store, procs.url(), db, "the file is not writable (Permission denied)");
  chmod(dir.c_str(), 0755);
}

TEST(MapstoreFaultsTest, ReadOnlyMountIsServedAndSavesFailSayingWhy) {
  const std::string why = EnterPrivateMountNamespace();
  if (!why.empty()) GTEST_SKIP() << "no private mount namespace: " << why;
  ProcessSet procs(cairn::testing::PrivateLcmUrl());
  const std::string dir = procs.dir() + "/ro-mount";
  fs::create_directories(dir);
  const std::string db = dir + "/site.db";
  MakeDatabase(db);
  // The folder bound onto itself, then that bind made read-only.
  MountGuard guard;
  ASSERT_EQ(mount(dir.c_str(), dir.c_str(), nullptr, MS_BIND, nullptr), 0) << std::strerror(errno);
  guard.dir = dir;
  ASSERT_EQ(mount(nullptr, dir.c_str(), nullptr, MS_BIND | MS_REMOUNT | MS_RDONLY, nullptr), 0)
      << std::strerror(errno);
  ASSERT_LT(open((dir + "/probe").c_str(), O_CREAT | O_WRONLY, 0644), 0);
  ASSERT_EQ(errno, EROFS) << "the mount is not read-only";
  ChildProcess& store = procs.Start("cairn-mapstore", {"--db", db});
  ExpectServedReadOnly(store, procs.url(), db, "Read-only file system");
  // cairn-map reads it too (its check opens the file read-only: no lock, no -shm).
  const CliResult check = RunCli(procs, {"check", "--db", db});
  EXPECT_EQ(check.exit_code, 0) << check.output;
  EXPECT_NE(check.output.find(": ok"), std::string::npos) << check.output;
}

TEST(MapstoreFaultsTest, FullDiskDuringASaveLosesNothingAndASaveSucceedsOnceThereIsRoom) {
  const std::string why = EnterPrivateMountNamespace();
  if (!why.empty()) GTEST_SKIP() << "no private mount namespace: " << why;
  ProcessSet procs(cairn::testing::PrivateLcmUrl());
  const std::string dir = procs.dir() + "/disk";
  fs::create_directories(dir);
  MountGuard guard;
  ASSERT_EQ(mount("tmpfs", dir.c_str(), "tmpfs", 0, "size=8m,mode=0755"), 0)
      << std::strerror(errno);
  guard.dir = dir;
  const std::string db = dir + "/site.db";
  ChildProcess& store = procs.Start("cairn-mapstore", {"--db", db});
  lcm::LCM lcm(procs.url());
  MapstoreClient client(lcm, "full-disk-test", TestClientOptions());
  ASSERT_TRUE(WaitForStore(client));
  const MapSnapshot north = TerrainSnapshot("lab", "north", 260, 240, 1.f);
  const MapSnapshot south = TerrainSnapshot("lab", "south", 260, 240, 2.f);
  for (const MapSnapshot* s : {&north, &south}) {
    auto saved = client.Save(*s);
    ASSERT_TRUE(saved.ok() && saved->status == kStatusOk)
        << (saved.ok() ? saved->message : saved.status().ToString());
  }

  // Fill the disk to the last byte.
  const std::string filler = dir + "/filler";
  int64_t filled = 0;
  {
    const int fd = open(filler.c_str(), O_CREAT | O_WRONLY | O_TRUNC, 0644);
    ASSERT_GE(fd, 0) << std::strerror(errno);
    const std::string chunk(4096, 'x');
    while (true) {
      const ssize_t n = write(fd, chunk.data(), chunk.size());
      if (n <= 0) break;
      filled += n;
    }
    EXPECT_EQ(errno, ENOSPC);
    close(fd);
  }
  std::printf("[ info ] filler took %lld bytes of the 8 MB tmpfs\n",
              static_cast<long long>(filled));

  // A save that needs room: refused with "disk full" and the file; nothing of it stored.
  const MapSnapshot big = NoisySnapshot("north");
  auto failed = client.Save(big);
  ASSERT_TRUE(failed.ok()) << failed.status().ToString();
  EXPECT_EQ(failed->status, kStatusError) << failed->message;
  for (const std::string& part : {std::string("disk full"), "'" + db + "'",
                                  std::string("everything committed before is intact")}) {
    EXPECT_NE(failed->message.find(part), std::string::npos) << part << " in: " << failed->message;
  }
  std::printf("[ info ] save on a full disk: %s\n", failed->message.c_str());
  EXPECT_TRUE(LogHas(store, "save of lab/north failed: RESOURCE_EXHAUSTED")) << store.Log();

  // The service keeps running and serves the earlier versions, whole.
  EXPECT_TRUE(store.Running());
  ExpectLoads(client, "north", 0, north);
  ExpectLoads(client, "south", 0, south);
  auto list = client.Call(MakeRequest(Request::OP_LIST_MAPS, "lab", "north"));
  ASSERT_TRUE(list.ok());
  EXPECT_EQ(list->num_maps, 1) << "the failed save left a version behind";

  // Room again: the same save succeeds, as version 2, and everything reads back.
  ASSERT_EQ(unlink(filler.c_str()), 0);
  auto saved = client.Save(big);
  ASSERT_TRUE(saved.ok()) << saved.status().ToString();
  ASSERT_EQ(saved->status, kStatusOk) << saved->message;
  EXPECT_EQ(saved->version, 2);
  ExpectLoads(client, "north", 2, big);
  ExpectLoads(client, "north", 1, north);
  const CliResult check = RunCli(procs, {"check", "--db", db});
  EXPECT_EQ(check.exit_code, 0) << check.output;
  EXPECT_NE(check.output.find(": ok"), std::string::npos) << check.output;
  store.Stop();
}

// Where the stored bytes of a blob of `map` lie in the file: the byte offset of 64 bytes from
// its middle, and the blob's "layer/tx/ty". The file must hold the blob itself (no WAL).
struct BlobPlace {
  std::string tile;
  int64_t offset{-1};
};

BlobPlace FindBlobInFile(const std::string& db, const MapRef& ref) {
  SqliteOptions read_only;
  read_only.read_only = true;
  auto store = SqliteMapStore::Open(db, read_only);
  if (!store.ok()) return {};
  auto blobs = (*store)->BaseBlobBytes(ref);
  if (!blobs.ok() || blobs->empty()) return {};
  // The largest blob spans overflow pages; 64 bytes from its middle lie on one of them.
  auto largest = blobs->begin();
  for (auto it = blobs->begin(); it != blobs->end(); ++it) {
    if (it->second.size() > largest->second.size()) largest = it;
  }
  const std::string& bytes = largest->second;
  const std::string file = ReadAll(db);
  // A run that straddles two overflow pages is not contiguous in the file: try a few.
  for (size_t from = bytes.size() / 2; from + 64 <= bytes.size(); from += 1000) {
    const std::string needle = bytes.substr(from, 64);
    const size_t at = file.find(needle);
    if (at != std::string::npos && file.find(needle, at + 1) == std::string::npos) {
      return {largest->first, static_cast<int64_t>(at)};
    }
  }
  return {};
}

// What dbstat says page `page` is: "<table>/<page type>".
std::string PageKind(const std::string& db, int64_t page) {
  sqlite3* raw = nullptr;
  if (sqlite3_open_v2(db.c_str(), &raw, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) return "";
  sqlite3_stmt* st = nullptr;
  std::string kind;
  if (sqlite3_prepare_v2(raw, "SELECT name, pagetype FROM dbstat WHERE pageno = ?", -1, &st,
                         nullptr) == SQLITE_OK) {
    sqlite3_bind_int64(st, 1, page);
    if (sqlite3_step(st) == SQLITE_ROW) {
      kind = std::string(reinterpret_cast<const char*>(sqlite3_column_text(st, 0))) + "/" +
             reinterpret_cast<const char*>(sqlite3_column_text(st, 1));
    }
  }
  sqlite3_finalize(st);
  sqlite3_close(raw);
  return kind;
}

TEST(MapstoreFaultsTest, ADamagedPageIsNamedByCheckAndOnlyItsMapIsRefused) {
  ProcessSet procs(cairn::testing::PrivateLcmUrl());
  const std::string db = procs.dir() + "/site.db";
  lcm::LCM lcm(procs.url());
  MapstoreClient client(lcm, "damage-test", TestClientOptions());
  const MapSnapshot victim = TerrainSnapshot("lab", "victim", 260, 240, 1.f);
  const MapSnapshot other = TerrainSnapshot("lab", "other", 260, 240, 2.f);
  {
    // Saved through a service, which then stops: the WAL is folded into the file.
    ChildProcess& first = procs.Start("cairn-mapstore", {"--db", db});
    ASSERT_TRUE(WaitForStore(client));
    for (const MapSnapshot* s : {&victim, &other}) {
      auto saved = client.Save(*s);
      ASSERT_TRUE(saved.ok() && saved->status == kStatusOk);
    }
    first.Stop();
  }
  ASSERT_FALSE(fs::exists(db + "-wal")) << "the stopped service left its WAL";
  const BlobPlace place = FindBlobInFile(db, {"lab", "victim", 1});
  ASSERT_GE(place.offset, 0) << "no blob of lab/victim found once in the file";
  constexpr int64_t kPageSize = 8192;
  const int64_t page = place.offset / kPageSize + 1;
  EXPECT_EQ(PageKind(db, page), "blobs/overflow") << "page " << page;
  std::printf("[ info ] damaging page %lld (%s), inside the blob of lab/victim %s\n",
              static_cast<long long>(page), PageKind(db, page).c_str(), place.tile.c_str());

  // A service runs on the file; it has listed the maps but not read the victim's tiles.
  ChildProcess& store = procs.Start("cairn-mapstore", {"--db", db});
  ASSERT_TRUE(WaitForStore(client));
  auto listed = client.Call(MakeRequest(Request::OP_LIST_MAPS, "lab"));
  ASSERT_TRUE(listed.ok());
  ASSERT_EQ(listed->num_maps, 2);

  // Another program writes over 64 bytes of that page of the running database.
  {
    const int fd = open(db.c_str(), O_WRONLY);
    ASSERT_GE(fd, 0);
    const std::string garbage(64, '\x5a');
    ASSERT_EQ(pwrite(fd, garbage.data(), garbage.size(), place.offset), 64);
    close(fd);
  }

  // The damaged map is refused as CORRUPT, naming the map, the layer, the tile and the file ...
  auto loaded = client.Load("lab", "victim", 0, "");
  ASSERT_FALSE(loaded.ok());
  EXPECT_EQ(loaded.status().code(), common::StatusCode::kCorrupt) << loaded.status().ToString();
  // "layer/tx/ty", the layer's name perhaps with slashes of its own.
  const size_t last = place.tile.rfind('/');
  const size_t middle = place.tile.rfind('/', last - 1);
  const std::string layer = place.tile.substr(0, middle);
  const std::string tile = "(" + place.tile.substr(middle + 1, last - middle - 1) + ", " +
                           place.tile.substr(last + 1) + ")";
  for (const std::string& part : {std::string("lab/victim"), "layer '" + layer + "'",
                                  "'" + db + "'", std::string("cairn-map check")}) {
    EXPECT_NE(loaded.status().message().find(part), std::string::npos)
        << part << " in: " << loaded.status().message();
  }
  std::printf("[ info ] load of the damaged map: %s\n", loaded.status().message().c_str());
  auto raw = client.Call(MakeRequest(Request::OP_LOAD, "lab", "victim"));
  ASSERT_TRUE(raw.ok());
  EXPECT_EQ(raw->status, kStatusCorrupt);
  // ... while the other map is served as before, and the service keeps running.
  ExpectLoads(client, "other", 0, other);
  EXPECT_TRUE(store.Running());

  // cairn-map check names the damaged map, layer and tile, and only that map.
  const CliResult check = RunCli(procs, {"check", "--db", db});
  EXPECT_EQ(check.exit_code, 1) << check.output;
  EXPECT_NE(check.output.find("map lab/victim v1 layer " + layer + " tile " + tile),
            std::string::npos)
      << check.output;
  EXPECT_EQ(check.output.find("lab/other"), std::string::npos) << check.output;
  EXPECT_NE(check.output.find("DAMAGED"), std::string::npos) << check.output;
  std::printf("[ info ] cairn-map check:\n%s\n", check.output.c_str());
}

}  // namespace
}  // namespace cairn::mapstore::testing
