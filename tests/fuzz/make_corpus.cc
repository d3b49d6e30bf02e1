// fuzz_make_corpus: writes the seed corpora of the fuzz targets (tests/fuzz/corpus/<target>).
//
//   fuzz_make_corpus --log DEMO.lcmlog --config CONFIG_DIR --db FILE... --out CORPUS_ROOT
//
// - lcm_decode: up to two recorded messages of every type the log holds, behind the index of
//   their type (found by fingerprint), up to 64 KB each;
// - bus_*: runs of consecutive recorded messages on the target's channels, framed as FeedBus
//   reads them, spread over the log (every map store request starts one);
// - codecs: recorded compressed tiles as blobs, and recorded registries in the store's format;
// - assemblers: operation sequences from a fixed seed (they have no recorded form);
// - yaml_loaders: every shipped configuration file behind the index of its loader;
// - sqlite_open: the database files given, and a small database of the current schema.
// Recorded logs come from scripts/record beside scripts/demo (tests/fuzz/README.md).

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include "cairn/lcmt_sim_control_request.hpp"
#include "cairn/lcmt_velocity_command.hpp"
#include "mapstore/blob_codec.h"
#include "mapstore/lcm/tile_wire.h"
#include "mapstore/registry_codec.h"
#include "mapstore/sqlite_map_store.h"
#include "services/runtime/conversions.h"
#include "tests/fuzz/bus_channels.h"
#include "tests/fuzz/bus_feed.h"
#include "tests/fuzz/lcm_types.h"
#include "tests/unit/mapstore/fake_deriver.h"

namespace fs = std::filesystem;

namespace {

constexpr size_t kMaxSeedBytes = 96 * 1024;

void Write(const fs::path& dir, const std::string& name, const std::string& bytes) {
  fs::create_directories(dir);
  std::ofstream(dir / name, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

int64_t HashOf(const void* data, size_t size) {
  if (size < 8) return 0;
  const auto* b = static_cast<const uint8_t*>(data);
  uint64_t h = 0;
  for (int i = 0; i < 8; ++i) h = (h << 8) | b[i];
  return static_cast<int64_t>(h);
}

#define CAIRN_HASH(T) cairn::T::getHash(),
const std::vector<int64_t> kHashes = {CAIRN_FUZZ_LCM_TYPES(CAIRN_HASH)};
#undef CAIRN_HASH

struct Message {
  std::string channel;
  std::string data;
};

std::vector<Message> ReadLog(const std::string& path) {
  lcm::LogFile log(path, "r");
  if (!log.good()) {
    std::fprintf(stderr, "make_corpus: cannot read %s\n", path.c_str());
    std::exit(1);
  }
  std::vector<Message> out;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    out.push_back({e->channel, std::string(static_cast<const char*>(e->data),
                                           static_cast<size_t>(e->datalen))});
  }
  return out;
}

void LcmDecodeSeeds(const std::vector<Message>& log, const fs::path& out) {
  std::map<size_t, int> taken;
  for (const Message& m : log) {
    if (m.data.size() > kMaxSeedBytes) continue;
    const int64_t hash = HashOf(m.data.data(), m.data.size());
    for (size_t i = 0; i < kHashes.size(); ++i) {
      if (kHashes[i] != hash || taken[i] >= 2 || m.data.size() > 64 * 1024) continue;
      const std::string seed = std::string(1, static_cast<char>(i)) + m.data;
      Write(out, "rec-" + std::to_string(i) + "-" + std::to_string(taken[i]++), seed);
    }
  }
  std::printf("lcm_decode: %zu types\n", taken.size());
}

void BusSeeds(const std::vector<Message>& log, const std::string& target, const fs::path& out) {
  const std::vector<std::string> channels = cairn::fuzz::BusChannels(target);
  std::vector<std::pair<size_t, uint8_t>> on;  // (log index, channel index)
  for (size_t i = 0; i < log.size(); ++i) {
    for (size_t c = 0; c < channels.size(); ++c) {
      if (log[i].channel == channels[c]) on.push_back({i, static_cast<uint8_t>(c)});
    }
  }
  constexpr size_t kSeeds = 8, kFrames = 8;
  std::vector<size_t> starts;
  for (size_t k = 0; k < kSeeds && !on.empty(); ++k) starts.push_back(k * on.size() / kSeeds);
  std::vector<bool> channel_started(channels.size(), false);
  for (size_t j = 0; j < on.size(); ++j) {  // the first message of every channel starts one
    if (!channel_started[on[j].second]) starts.push_back(j);
    channel_started[on[j].second] = true;
  }
  for (size_t j = 0; j < on.size(); ++j) {  // every store request, reply and manifest starts one
    const std::string& channel = log[on[j].first].channel;
    if (channel == cairn::channels::kMapstoreRequest ||
        (target == "bus_mapstore_client" && (channel == cairn::channels::kMapstoreReply ||
                                             channel == cairn::channels::kMapstoreManifest))) {
      starts.push_back(j);
    }
  }
  int written = 0;
  for (size_t s : starts) {
    std::string seed;
    for (size_t j = s; j < on.size() && j < s + kFrames; ++j) {
      const std::string& data = log[on[j].first].data;
      if (!seed.empty() && seed.size() + data.size() > kMaxSeedBytes) break;
      cairn::fuzz::AppendFrame(on[j].second, data.data(), data.size(), &seed);
    }
    if (!seed.empty()) Write(out, "rec-" + std::to_string(written++), seed);
  }
  std::printf("%s: %d seeds from %zu messages\n", target.c_str(), written, on.size());
}

// The codecs target's header: pick, codec, raw size, CRC, verify (ByteReader::Range encodes a
// value v of [lo, hi] as v - lo).
std::string CodecHeader(int pick, int codec, int64_t raw_size, uint32_t crc) {
  std::string h;
  auto put32 = [&](uint32_t v) { h.append(reinterpret_cast<const char*>(&v), 4); };
  put32(static_cast<uint32_t>(pick));
  put32(static_cast<uint32_t>(codec));
  put32(static_cast<uint32_t>(raw_size + 1));
  put32(crc);
  h.push_back(1);
  return h;
}

void CodecSeeds(const std::vector<Message>& log, const fs::path& out) {
  int tiles = 0, registries = 0;
  for (const Message& m : log) {
    const int64_t hash = HashOf(m.data.data(), m.data.size());
    if (hash == cairn::lcmt_grid_tile_batch::getHash() && tiles < 6) {
      cairn::lcmt_grid_tile_batch batch;
      if (batch.decode(m.data.data(), 0, static_cast<int>(m.data.size())) < 0) continue;
      for (const auto& t : batch.tiles) {
        const auto codec = cairn::mapstore::CodecOfEncoding(t.encoding);
        if (!codec || tiles >= 6) continue;
        const std::string bytes(t.bytes.begin(), t.bytes.end());
        const int64_t raw = int64_t{t.cells_x} * t.cells_y * 4;
        Write(out, "tile-" + std::to_string(tiles++),
              CodecHeader(0, static_cast<int>(*codec), raw, static_cast<uint32_t>(t.checksum)) +
                  bytes);
      }
    } else if (hash == cairn::lcmt_obstacle_registry::getHash() && registries < 4) {
      cairn::lcmt_obstacle_registry msg;
      if (msg.decode(m.data.data(), 0, static_cast<int>(m.data.size())) < 0) continue;
      auto registry = cairn::runtime::FromLcm(msg);
      if (!registry.ok() || registry->obstacles.empty()) continue;
      Write(out, "registry-" + std::to_string(registries++),
            CodecHeader(2, 0, 0, 0) + cairn::mapstore::SerializeRegistry(*registry));
    }
  }
  std::printf("codecs: %d tiles, %d registries\n", tiles, registries);
}

// SIM.CONTROL has no traffic in the demo's log: one request of every op, each after a
// velocity command, framed for bus_sim (its channel 0 is CMD_VEL, 2 is SIM.CONTROL).
void SimControlSeeds(const fs::path& out) {
  using Request = cairn::lcmt_sim_control_request;
  const std::vector<std::pair<int8_t, std::string>> ops = {
      {Request::OP_SPAWN, "box1"},         {Request::OP_MOVE, "box1"},
      {Request::OP_REMOVE, "box1"},        {Request::OP_OPEN_DOOR, "door1"},
      {Request::OP_CLOSE_DOOR, "door1"},   {Request::OP_RESET_ROBOT, "p3at"},
      {Request::OP_PAUSE, ""},             {Request::OP_RESUME, ""},
      {Request::OP_SET_SPEED, ""},         {Request::OP_LIST, ""},
      {Request::OP_TRIGGER_SENSOR, "p3at/lidar"}};
  cairn::lcmt_velocity_command cmd{};
  cmd.robot = cairn::fuzz::kRobot;
  cmd.linear_mps = 0.3;
  cmd.angular_radps = 0.1;
  cmd.source = "fuzz";
  std::string cmd_bytes(static_cast<size_t>(cmd.getEncodedSize()), '\0');
  cmd.encode(cmd_bytes.data(), 0, static_cast<int>(cmd_bytes.size()));
  int written = 0;
  for (const auto& [op, name] : ops) {
    Request r{};
    r.utime = 1000000;
    r.request_id = 100 + op;
    r.requester = "fuzz";
    r.op = op;
    r.name = name;
    r.shape = Request::SHAPE_BOX;
    r.size_m[0] = r.size_m[1] = r.size_m[2] = 0.5;
    r.position_m[0] = 6.0;
    r.position_m[1] = 38.0;
    r.position_m[2] = 0.5;
    r.speed = 2.0;
    std::string bytes(static_cast<size_t>(r.getEncodedSize()), '\0');
    r.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    std::string seed;
    cairn::fuzz::AppendFrame(0, cmd_bytes.data(), cmd_bytes.size(), &seed);
    cairn::fuzz::AppendFrame(2, bytes.data(), bytes.size(), &seed);
    Write(out, "control-" + std::to_string(written++), seed);
  }
  std::printf("bus_sim: %d SIM.CONTROL seeds\n", written);
}

void AssemblerSeeds(const fs::path& out) {
  std::mt19937 rng(20261206);
  for (int i = 0; i < 12; ++i) {
    std::string seed(512 + 256 * (i % 4), '\0');
    for (char& c : seed) c = static_cast<char>(rng());
    seed[0] = static_cast<char>(i % 3);
    Write(out, "gen-" + std::to_string(i), seed);
  }
}

void YamlSeeds(const fs::path& config, const fs::path& out) {
  const std::vector<std::pair<std::string, int>> folders = {
      {"profiles", 0}, {"mapping", 1}, {"navigator", 2}, {"explore", 3},
      {"mapstore", 4}, {"sim", 5},     {"graphs", 6}};
  int n = 0;
  for (const auto& [folder, pick] : folders) {
    if (!fs::is_directory(config / folder)) continue;
    for (const auto& entry : fs::directory_iterator(config / folder)) {
      if (entry.path().extension() != ".yaml") continue;
      std::ifstream in(entry.path(), std::ios::binary);
      const std::string text((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
      Write(out, folder + "-" + entry.path().stem().string(),
            std::string(1, static_cast<char>(pick)) + text);
      ++n;
    }
  }
  std::printf("yaml_loaders: %d files\n", n);
}

void SqliteSeeds(const std::vector<std::string>& dbs, const fs::path& out) {
  for (const std::string& db : dbs) {
    std::ifstream in(db, std::ios::binary);
    Write(out, fs::path(db).filename().string(),
          std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()));
  }
  const fs::path path = fs::temp_directory_path() / ("cairn-corpus-" + std::to_string(getpid()));
  {
    auto store = cairn::mapstore::SqliteMapStore::Open(path.string());
    if (!store.ok()) std::exit(1);
    cairn::mapstore::WriteContext ctx;
    ctx.actor = "fuzz_make_corpus";
    (void)(*store)->PutProfile(cairn::mapstore::testing::Profile("pioneer3at", 8.0, 0.03), ctx);
    (void)(*store)->SaveMap(cairn::mapstore::testing::SampleSnapshot("corridor", 30, 20), ctx);
    (*store)->CheckpointIfIdle(0.0);
  }
  std::ifstream in(path, std::ios::binary);
  Write(out, "current-schema.db",
        std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()));
  for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(path.string() + suffix);
  std::printf("sqlite_open: %zu files\n", dbs.size() + 1);
}

}  // namespace

int main(int argc, char** argv) {
  std::string log_path, config, out_root;
  std::vector<std::string> dbs;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--log")
      log_path = argv[i + 1];
    else if (flag == "--config")
      config = argv[i + 1];
    else if (flag == "--db")
      dbs.push_back(argv[i + 1]);
    else if (flag == "--out")
      out_root = argv[i + 1];
  }
  if (argc < 2 || std::string(argv[1]) == "--help" || log_path.empty() || out_root.empty()) {
    std::fprintf(stderr,
                 "usage: fuzz_make_corpus --log DEMO.lcmlog --config CONFIG_DIR --db FILE... "
                 "--out CORPUS_ROOT\n");
    return 2;
  }
  const fs::path root(out_root);
  const std::vector<Message> log = ReadLog(log_path);
  LcmDecodeSeeds(log, root / "lcm_decode");
  for (const char* target : {"bus_navigator_map", "bus_mapper", "bus_mapstore", "bus_launcher",
                             "bus_explorer", "bus_mapstore_client", "bus_sim"}) {
    BusSeeds(log, target, root / target);
  }
  SimControlSeeds(root / "bus_sim");
  CodecSeeds(log, root / "codecs");
  AssemblerSeeds(root / "assemblers");
  if (!config.empty()) YamlSeeds(config, root / "yaml_loaders");
  SqliteSeeds(dbs, root / "sqlite_open");
  return 0;
}
