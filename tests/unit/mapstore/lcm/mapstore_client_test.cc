// MapstoreClient's subscriptions: what arrives on its channels is decoded and handled inside a
// guard, so a malformed message is counted and dropped, and no handler's exception unwinds
// through liblcm's C dispatch (issue 20).

#include "mapstore/lcm/mapstore_client.h"

#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "cairn/lcmt_mapstore_reply.hpp"
#include "common/channels.h"

namespace cairn::mapstore {
namespace {

TEST(MapstoreClientTest, MalformedMessagesOnItsChannelsAreCountedAndDropped) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  MapstoreClient client(lcm, "mapstore_client_test");
  const std::vector<uint8_t> garbage = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  for (const char* channel :
       {channels::kMapstoreReply, channels::kMapstoreTiles, channels::kMapstoreTileBatches,
        channels::kMapstoreManifest, channels::kMapstoreOctomap,
        channels::kMapstorePushTileResend}) {
    lcm.publish(channel, garbage.data(), static_cast<unsigned>(garbage.size()));
  }
  // A reply with the right fingerprint but a count its bytes cannot hold.
  cairn::lcmt_mapstore_reply reply{};
  std::vector<uint8_t> bytes(reply.getEncodedSize());
  reply.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  bytes.resize(bytes.size() - 2);  // cut short
  lcm.publish(channels::kMapstoreReply, bytes.data(), static_cast<unsigned>(bytes.size()));
  while (lcm.handleTimeout(0) > 0) {
  }
  EXPECT_EQ(client.dropped_messages(), 7);
}

}  // namespace
}  // namespace cairn::mapstore
