// The map store's byte formats: blobs of every codec (DecodeBlob, DecodeFloatBlobRows into a
// place smaller than the blob), the registry, parts and polygon encodings, and the blob a
// stored tile claims to be (CheckStoredTile). Damaged bytes give a status, never a crash.

#include <string>
#include <vector>

#include "mapstore/blob_codec.h"
#include "mapstore/registry_codec.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace ms = cairn::mapstore;
  cairn::fuzz::ByteReader in(data, size);
  const int pick = static_cast<int>(in.Range(0, 4));
  const auto codec = static_cast<ms::Codec>(in.Range(0, 4));  // 4: no such codec
  const int64_t raw_size = in.Range(-1, 1 << 20);
  const auto crc = in.Read<uint32_t>();
  const bool verify = in.Read<uint8_t>() & 1;
  switch (pick) {
    case 0: {
      (void)ms::DecodeBlob(codec, in.Rest(), raw_size, crc, verify);
      break;
    }
    case 1: {
      const int cells_x = static_cast<int>(in.Range(0, 300));
      const int cells_y = static_cast<int>(in.Range(0, 300));
      std::vector<float> place(100 * 100);
      ms::FloatRows rows;
      rows.first = place.data();
      rows.row_stride = 100;
      rows.cells_per_row = std::min(cells_x, 100);
      rows.rows = std::min(cells_y, 100);
      const std::string bytes = in.Rest();
      (void)ms::DecodeFloatBlobRows(codec, bytes.data(), bytes.size(), cells_x, cells_y, crc, rows,
                                    verify);
      break;
    }
    case 2: {
      const std::string bytes = in.Rest();
      auto registry = ms::ParseRegistry(bytes);
      // What parses serializes and parses back to the same.
      if (registry.ok()) {
        auto again = ms::ParseRegistry(ms::SerializeRegistry(*registry));
        if (!again.ok() || again->obstacles.size() != registry->obstacles.size()) std::abort();
      }
      break;
    }
    case 3: {
      const std::string bytes = in.Rest();
      (void)ms::ParseParts(bytes);
      (void)ms::ParsePolygon(bytes);
      break;
    }
    default: {
      ms::StoredTile tile;
      tile.cells_x = static_cast<int>(in.Range(-1, 200));
      tile.cells_y = static_cast<int>(in.Range(-1, 200));
      tile.codec = static_cast<int>(codec);
      tile.raw_crc32 = crc;
      tile.data = in.Rest();
      (void)ms::CheckStoredTile(tile);
      break;
    }
  }
  return 0;
}
