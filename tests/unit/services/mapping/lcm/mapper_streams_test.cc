// The registered sensor streams: one converter per stream (the service subscribes to those the
// layers take; MapperServiceTest.PublishesALayerAddedThroughTheSeam runs one end to end).

#include "services/mapping/lcm/mapper_streams.h"

#include <set>

#include <gtest/gtest.h>

namespace cairn::mapping {
namespace {

TEST(MapperStreamsTest, OneConverterPerStream) {
  std::set<std::string> streams;
  for (const StreamConverter& c : RegisteredStreams()) {
    EXPECT_FALSE(c.stream.empty());
    EXPECT_TRUE(static_cast<bool>(c.convert)) << c.stream;
    EXPECT_TRUE(streams.insert(c.stream).second) << c.stream << " is registered twice";
    // Bytes that are no message are refused, never a crash.
    const char garbage[] = "not a message";
    EXPECT_FALSE(c.convert(garbage, sizeof(garbage)).ok()) << c.stream;
  }
}

}  // namespace
}  // namespace cairn::mapping
