// The map store's client (cairn-mission's, cairn-explorer's and cairn-map's side of the store
// protocol): MapstoreClient::Load and a push save's wait, on memq://, answered by a stand-in
// store on the same bus that plays the input's frames (replies, reply tiles, batches,
// manifests, OctoMap chunks, resend requests) when the request arrives. Frames that decode
// carry the live request id (the recorded one is replaced), so recorded answers reach the
// handlers as they would live; a channel byte with its top bit set sends the frame as it is.

#include <lcm/lcm-cpp.hpp>

#include <memory>
#include <regex>
#include <string>
#include <vector>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_grid_tile_batch.hpp"
#include "cairn/lcmt_mapstore_reply.hpp"
#include "cairn/lcmt_mapstore_request.hpp"
#include "cairn/lcmt_octomap.hpp"
#include "common/channels.h"
#include "mapstore/lcm/mapstore_client.h"
#include "tests/fuzz/bus_channels.h"
#include "tests/fuzz/fuzz_input.h"

namespace {

using cairn::fuzz::ByteReader;

// "<digits>/rest" -> "<id>/rest": reply layers are named after the request they answer.
std::string WithRequestId(const std::string& name, int64_t id) {
  const auto slash = name.find('/');
  if (slash == std::string::npos || slash == 0) return name;
  for (size_t i = 0; i < slash; ++i) {
    if (name[i] < '0' || name[i] > '9') return name;
  }
  return std::to_string(id) + name.substr(slash);
}

template <typename Msg, typename Fix>
std::string Rewritten(const std::string& payload, Fix fix) {
  Msg msg;
  if (msg.decode(payload.data(), 0, static_cast<int>(payload.size())) < 0) return payload;
  fix(msg);
  std::string out(static_cast<size_t>(msg.getEncodedSize()), '\0');
  if (msg.encode(out.data(), 0, static_cast<int>(out.size())) < 0) return payload;
  return out;
}

std::string ForRequest(const std::string& channel, const std::string& payload, int64_t id) {
  namespace ch = cairn::channels;
  if (channel == ch::kMapstoreReply) {
    return Rewritten<cairn::lcmt_mapstore_reply>(payload, [&](auto& m) { m.request_id = id; });
  }
  if (channel == ch::kMapstoreTiles) {
    return Rewritten<cairn::lcmt_grid_tile>(
        payload, [&](auto& m) { m.map_name = WithRequestId(m.map_name, id); });
  }
  if (channel == ch::kMapstoreTileBatches) {
    return Rewritten<cairn::lcmt_grid_tile_batch>(
        payload, [&](auto& m) { m.map_name = WithRequestId(m.map_name, id); });
  }
  if (channel == ch::kMapstoreManifest) {
    return Rewritten<cairn::lcmt_grid_manifest>(
        payload, [&](auto& m) { m.map_name = WithRequestId(m.map_name, id); });
  }
  if (channel == ch::kMapstoreOctomap) {
    return Rewritten<cairn::lcmt_octomap>(
        payload, [&](auto& m) { m.map_name = WithRequestId(m.map_name, id); });
  }
  return payload;
}

// The stand-in store: on the first request, publishes every frame of the input.
class Player {
 public:
  Player(lcm::LCM& lcm, const uint8_t* data, size_t size) : lcm_(lcm), data_(data), size_(size) {
    sub_ = lcm_.subscribeFunction<Player*>(cairn::channels::kMapstoreRequest, &Player::OnRequest,
                                          this);
  }
  ~Player() { lcm_.unsubscribe(sub_); }

 private:
  static void OnRequest(const lcm::ReceiveBuffer* rbuf, const std::string&, Player* self) {
    if (self->played_) return;
    self->played_ = true;
    cairn::lcmt_mapstore_request request;
    if (request.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) return;
    static const std::vector<std::string> channels = cairn::fuzz::MapstoreClientChannels();
    ByteReader in(self->data_, self->size_);
    while (!in.empty()) {
      const auto pick = in.Read<uint8_t>();
      const std::string& channel = channels[(pick & 0x7f) % channels.size()];
      const uint32_t declared = in.Read<uint32_t>();
      const size_t n = std::min<size_t>(declared, in.remaining());
      std::string payload(n, '\0');
      for (size_t i = 0; i < n; ++i) payload[i] = static_cast<char>(in.Read<uint8_t>());
      if (!(pick & 0x80)) payload = ForRequest(channel, payload, request.request_id);
      self->lcm_.publish(channel, payload.data(), static_cast<unsigned>(payload.size()));
    }
  }

  lcm::LCM& lcm_;
  const uint8_t* data_;
  size_t size_;
  lcm::Subscription* sub_{nullptr};
  bool played_{false};
};

cairn::mapstore::MapstoreClientOptions Options() {
  cairn::mapstore::MapstoreClientOptions o;
  o.reply_timeout_s = 0.005;
  o.total_timeout_s = 0.03;
  o.resend_interval_s = 0.002;
  o.compression_threads = 1;
  o.decode_threads = 1;
  return o;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  lcm::LCM lcm("memq://");
  Player player(lcm, data, size);
  cairn::mapstore::MapstoreClient client(lcm, "fuzz", Options());
  // A profile's map with its OctoMap (every kind of reply layer), as the demo mission loads.
  (void)client.Load("tunnel", "demo", 0, "rover", {"octomap"});
  return 0;
}
