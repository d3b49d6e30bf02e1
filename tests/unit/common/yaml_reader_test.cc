#include "common/yaml_reader.h"

#include <gtest/gtest.h>

namespace cairn::common {
namespace {

TEST(YamlMapTest, ReadsAndRejectsUnknownKeys) {
  YamlMap map = YamlMap::FromString("a: 1\nb: hello\nc: {d: 2.5}\n", "cfg.yaml");
  EXPECT_EQ(map.Require<int>("a"), 1);
  std::string b;
  EXPECT_TRUE(map.Get("b", &b));
  EXPECT_EQ(b, "hello");
  YamlMap c = map.Child("c");
  EXPECT_DOUBLE_EQ(c.Require<double>("d"), 2.5);
  c.Finish();
  map.Finish();
}

TEST(YamlMapTest, UnknownKeyErrorHasLine) {
  YamlMap map = YamlMap::FromString("a: 1\nzz: 2\n", "cfg.yaml");
  map.Require<int>("a");
  try {
    map.Finish();
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "cfg.yaml:2: unknown key 'zz'");
  }
}

TEST(YamlMapTest, BadValueAndMissingKey) {
  YamlMap map = YamlMap::FromString("a: notanumber\n", "cfg.yaml");
  EXPECT_THROW(map.Require<int>("a"), ConfigError);
  EXPECT_THROW(map.Require<int>("missing"), ConfigError);
  EXPECT_THROW(YamlMap::FromString("[1, 2]", "x.yaml"), ConfigError);
  EXPECT_THROW(YamlMap::FromString("a: [1, 2", "x.yaml"), ConfigError);
  EXPECT_THROW(YamlMap::LoadFile("/nonexistent/file.yaml"), ConfigError);
}

TEST(YamlMapTest, AKeyGivenTwiceIsRefusedWithItsLine) {
  try {
    YamlMap::FromString("a: 1\nb: 2\na: 3\n", "cfg.yaml");
    FAIL() << "accepted a duplicate key";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "cfg.yaml:3: key 'a' given twice");
  }
  // Nested maps too, named by their path.
  YamlMap outer = YamlMap::FromString("p:\n  command: x\n  command: y\n", "g.yaml");
  try {
    outer.Child("p");
    FAIL() << "accepted a duplicate nested key";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "g.yaml:3: key 'p.command' given twice");
  }
}

}  // namespace
}  // namespace cairn::common
