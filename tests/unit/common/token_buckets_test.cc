#include "common/token_buckets.h"

#include <string>

#include <gtest/gtest.h>

namespace cairn::common {
namespace {

TokenBucketsParams Params() {
  TokenBucketsParams p;
  p.rate_per_s = 10.0;
  p.burst = 20.0;
  p.total_rate_per_s = 25.0;
  p.total_burst = 50.0;
  p.max_requesters = 4;
  return p;
}

TEST(TokenBucketsTest, ARequesterGetsItsBurstThenItsRate) {
  TokenBuckets dut(Params());
  EXPECT_TRUE(dut.Allow("nav", 20.0, 0.0));
  EXPECT_FALSE(dut.Allow("nav", 1.0, 0.0));  // the burst is spent
  EXPECT_FALSE(dut.Allow("nav", 6.0, 0.5));  // half a second gives 5
  EXPECT_TRUE(dut.Allow("nav", 5.0, 0.5));
  EXPECT_TRUE(dut.Allow("nav", 20.0, 100.0));  // refills to the burst, no more
  EXPECT_FALSE(dut.Allow("nav", 1.0, 100.0));
  EXPECT_EQ(dut.refused(), 3);
}

// Issue 20: resend requests were not rate-limited. Many names from one peer share the total.
TEST(TokenBucketsTest, ManyRequestersTogetherGetTheTotalAndNoMore) {
  TokenBuckets dut(Params());
  int granted = 0;
  for (int i = 0; i < 100; ++i) granted += dut.Allow("name" + std::to_string(i), 10.0, 0.0);
  EXPECT_EQ(granted, 5);  // the total burst: 50 tokens
  // A second later the total has 25 more.
  granted = 0;
  for (int i = 100; i < 200; ++i) granted += dut.Allow("name" + std::to_string(i), 10.0, 1.0);
  EXPECT_EQ(granted, 2);
}

TEST(TokenBucketsTest, ATimeThatGoesBackGivesNothing) {
  TokenBuckets dut(Params());
  EXPECT_TRUE(dut.Allow("nav", 20.0, 10.0));
  EXPECT_FALSE(dut.Allow("nav", 1.0, 5.0));
  EXPECT_FALSE(dut.Allow("nav", 1.0, 10.0));
}

TEST(TokenBucketsTest, BadParametersAreRefused) {
  TokenBucketsParams p = Params();
  p.rate_per_s = 0.0;
  EXPECT_THROW(TokenBuckets{p}, std::invalid_argument);
}

}  // namespace
}  // namespace cairn::common
