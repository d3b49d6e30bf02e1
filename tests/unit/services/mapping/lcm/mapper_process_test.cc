// The process steps around MapperService: the bus URL a live mapper opens.

#include "services/mapping/lcm/mapper_process.h"

#include <gtest/gtest.h>

namespace cairn::mapping {
namespace {

TEST(MapperLcmUrlTest, ALargeReceiveBufferOnUdpmOnly) {
  EXPECT_EQ(MapperLcmUrl("udpm://239.255.76.67:7667"),
            "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304");
  EXPECT_EQ(MapperLcmUrl("udpm://239.255.76.67:7667?ttl=1"),
            "udpm://239.255.76.67:7667?ttl=1&recv_buf_size=4194304");
  // A buffer size given is kept; other providers are left alone.
  EXPECT_EQ(MapperLcmUrl("udpm://239.255.76.67:7667?ttl=0&recv_buf_size=65536"),
            "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=65536");
  EXPECT_EQ(MapperLcmUrl("memq://"), "memq://");
}

}  // namespace
}  // namespace cairn::mapping
