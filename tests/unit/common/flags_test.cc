#include "common/flags.h"

#include <gtest/gtest.h>

namespace cairn::common {
namespace {

int ParseArgs(FlagParser& parser, std::vector<std::string> args) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  return parser.Parse(static_cast<int>(argv.size()), argv.data());
}

TEST(FlagParserTest, ParsesEachForm) {
  std::string url;
  double speed = 1.0;
  bool verbose = false;
  int n = 3;
  FlagParser parser("prog", "does things");
  parser.AddString("lcm-url", &url, "bus");
  parser.AddDouble("speed", &speed, "factor");
  parser.AddBool("verbose", &verbose, "talk");
  parser.AddInt("n", &n, "count");
  EXPECT_EQ(ParseArgs(parser, {"prog", "--lcm-url", "memq://", "--speed=2.5", "--verbose", "--n", "7", "pos"}), -1);
  EXPECT_EQ(url, "memq://");
  EXPECT_DOUBLE_EQ(speed, 2.5);
  EXPECT_TRUE(verbose);
  EXPECT_EQ(n, 7);
  EXPECT_EQ(parser.positional(), std::vector<std::string>{"pos"});
}

TEST(FlagParserTest, ErrorsAndHelp) {
  double speed = 1.0;
  FlagParser parser("prog", "does things");
  parser.AddDouble("speed", &speed, "factor");
  parser.AddHelpSection("worlds", "  tunnel\n");
  EXPECT_EQ(ParseArgs(parser, {"prog", "--nope"}), 2);
  EXPECT_EQ(ParseArgs(parser, {"prog", "--speed", "fast"}), 2);
  EXPECT_EQ(ParseArgs(parser, {"prog", "--speed"}), 2);
  EXPECT_NE(parser.Usage().find("tunnel"), std::string::npos);
  EXPECT_NE(parser.Usage().find("--speed VALUE"), std::string::npos);
}

TEST(FlagParserTest, RepeatedStringList) {
  std::vector<std::string> robots;
  FlagParser parser("prog", "does things");
  parser.AddStringList("robot", &robots, "a robot");
  EXPECT_EQ(ParseArgs(parser, {"prog", "--robot", "a:kobuki", "--robot=b:p3dx"}), -1);
  EXPECT_EQ(robots, (std::vector<std::string>{"a:kobuki", "b:p3dx"}));
  EXPECT_NE(parser.Usage().find("(repeatable)"), std::string::npos);
}

}  // namespace
}  // namespace cairn::common
