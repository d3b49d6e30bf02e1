#include "services/runtime/channel_meter.h"

#include <string>

#include <gtest/gtest.h>

namespace cairn::runtime {
namespace {

TEST(ChannelMeterTest, ALiveChannelReadsItsRateAndAQuietOneDecays) {
  ChannelMeter meter(3.0);
  for (int i = 0; i < 100; ++i) meter.Record("r.POSE", 50, i * 0.02);  // 50 Hz for 2 s
  auto rates = meter.Rates(1.98);
  EXPECT_NEAR(rates.at("r.POSE").rate_hz, 50.0, 0.5);
  EXPECT_NEAR(rates.at("r.POSE").bandwidth_Bps, 2500.0, 50.0);
  EXPECT_EQ(rates.at("r.POSE").messages, 100);
  rates = meter.Rates(3.5);  // 1.5 s silent
  EXPECT_LT(rates.at("r.POSE").rate_hz, 30.0);
  EXPECT_NEAR(rates.at("r.POSE").last_age_s, 1.52, 1e-9);
}

// Issue 20: channel names come from the bus. cairn-launch and cairn-spy meter every channel
// they hear; a peer inventing a name per message grew their tables without bound. Beyond
// max_channels, new names are metered together as one.
TEST(ChannelMeterTest, APeerInventingChannelNamesCannotGrowTheTable) {
  ChannelMeter meter(3.0, 100);
  meter.Record("r.POSE", 10, 0.0);
  for (int i = 0; i < 100000; ++i) meter.Record("forged." + std::to_string(i), 10, 0.001 * i);
  meter.Record("r.POSE", 10, 100.0);  // a channel it knew is still told apart
  const auto rates = meter.Rates(100.0);
  EXPECT_EQ(rates.size(), 101u);  // 100 names and the rest together
  EXPECT_EQ(rates.at("r.POSE").messages, 2);
  EXPECT_EQ(rates.at(ChannelMeter::kOtherChannels).messages, 100000 - 99);
  EXPECT_EQ(meter.overflow_messages(), 100000 - 99);
}

}  // namespace
}  // namespace cairn::runtime
