// The receivers that put large data back together from small messages, driven by a sequence of
// operations read from the input: the tile assembler (tiles in place or whole, manifests, the
// layer taken), the lidar revolution assembler and the OctoMap chunk assembler. What they hold
// stays within their budgets, and a layer taken has the grid its manifest declared.

#include <string>
#include <vector>

#include "common/tile_assembler.h"
#include "mapstore/octomap_chunks.h"
#include "services/runtime/revolution_assembler.h"
#include "tests/fuzz/fuzz_input.h"

namespace {

using cairn::fuzz::ByteReader;

cairn::common::TileHeader Header(ByteReader& in) {
  cairn::common::TileHeader h;
  h.robot = "r1";
  h.map_name = "live";
  h.layer = in.Read<uint8_t>() % 2 ? "elevation" : "cost/rover";
  h.geometry.resolution_m = in.Read<uint8_t>() % 5 == 0 ? 0.0 : 0.1;
  h.geometry.size_x = static_cast<int>(in.Range(-2, 700));
  h.geometry.size_y = static_cast<int>(in.Range(-2, 700));
  h.tile_size = static_cast<int>(in.Range(-1, 260));
  h.tile_ix = static_cast<int>(in.Range(-1, 8));
  h.tile_iy = static_cast<int>(in.Range(-1, 8));
  h.cells_x = static_cast<int>(in.Range(-1, 260));
  h.cells_y = static_cast<int>(in.Range(-1, 260));
  h.tile_version = in.Read<int64_t>();
  h.checksum = in.Read<uint32_t>();
  return h;
}

void Tiles(ByteReader& in) {
  cairn::common::TileAssembler dut;
  std::vector<float> cells;
  while (!in.empty()) {
    switch (in.Read<uint8_t>() % 5) {
      case 0: {
        cairn::common::CheckedTile tile;
        tile.header = Header(in);
        cells.assign(static_cast<size_t>(in.Range(0, 260 * 260)), 1.f);
        tile.cells = cells.data();
        tile.num_cells = cells.size();
        dut.OnTile(tile);
        break;
      }
      case 1: {
        const cairn::common::TileHeader h = Header(in);
        if (auto slot = dut.BeginTile(h)) {
          if (slot->first != nullptr) {
            for (int y = 0; y < slot->cells_y; ++y) {
              for (int x = 0; x < slot->cells_x; ++x) slot->first[y * slot->row_stride + x] = 2.f;
            }
            dut.EndTile(h, in.Read<uint8_t>() & 1);
          }
        }
        break;
      }
      case 2: {
        const cairn::common::TileHeader h = Header(in);
        cairn::common::TileManifest m;
        m.robot = h.robot;
        m.map_name = h.map_name;
        m.layer = h.layer;
        m.layer_version = in.Read<int64_t>();
        m.geometry = h.geometry;
        m.tile_size = h.tile_size;
        const int n = static_cast<int>(in.Range(0, 80));
        for (int i = 0; i < n; ++i) {
          m.tiles.push_back({static_cast<int>(in.Range(-1, 8)), static_cast<int>(in.Range(-1, 8)),
                             in.Read<int64_t>(), in.Read<uint32_t>()});
        }
        dut.OnManifest(m);
        break;
      }
      case 3: {
        for (const std::string& layer : dut.layers()) {
          (void)dut.Missing(layer);
          (void)dut.MissingRequest(layer);
          auto map = dut.Layer(layer);
          auto geometry = dut.Geometry(layer);
          if (map && (!geometry || map->geometry() != *geometry)) std::abort();
        }
        break;
      }
      default:
        (void)dut.TakeLayer(in.Read<uint8_t>() % 2 ? "elevation" : "cost/rover");
        break;
    }
  }
}

void Revolutions(ByteReader& in) {
  cairn::runtime::RevolutionLimits limits;
  limits.max_points_pending = 20000;
  cairn::runtime::RevolutionAssembler dut(limits);
  int64_t clock_us = 0;
  while (!in.empty()) {
    cairn::common::LidarSlice s;
    s.robot = in.Read<uint8_t>() % 3 == 0 ? "r2" : "r1";
    s.revolution = in.Read<uint8_t>() % 4 == 0 ? in.Read<int64_t>() : in.Range(0, 5);
    s.slice_count = static_cast<int32_t>(in.Range(-1, 5000));
    s.slice_index = static_cast<int32_t>(in.Range(-1, 5000));
    s.points.resize(static_cast<size_t>(in.Range(0, 70000)));
    clock_us += in.Range(0, 1'000'000);
    dut.OnSlice(std::move(s), clock_us);
    if (dut.pending_points() > limits.max_points_pending) std::abort();
  }
}

void Octomaps(ByteReader& in) {
  cairn::mapstore::OctomapAssembler dut;
  while (!in.empty()) {
    cairn::mapstore::OctomapChunk c;
    c.version = in.Range(0, 3);
    c.chunk_count = static_cast<int32_t>(in.Range(-1, 70000));
    c.chunk_index = static_cast<int32_t>(in.Range(-1, 70000));
    c.total_bytes = in.Read<uint8_t>() % 4 == 0 ? in.Read<int64_t>() : in.Range(0, 4096);
    c.checksum = in.Read<uint32_t>();
    const std::string bytes = in.Bytes(2048);
    c.data = bytes.data();
    c.size = bytes.size();
    dut.Add(c);
    if (dut.held_bytes() > 2 * cairn::mapstore::OctomapAssembler::kMaxTotalBytes) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  ByteReader in(data, size);
  switch (in.Read<uint8_t>() % 3) {
    case 0:
      Tiles(in);
      break;
    case 1:
      Revolutions(in);
      break;
    default:
      Octomaps(in);
      break;
  }
  return 0;
}
