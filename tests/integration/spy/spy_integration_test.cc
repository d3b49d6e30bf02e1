// cairn-spy and the Java types jar against real traffic between real processes.

#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include <gtest/gtest.h>
#include <sys/wait.h>

#include "cairn/lcmtypes_registry.hpp"
#include "tests/support/harness.h"

namespace cairn::testing {
namespace {

std::string ShortName(const std::string& full) { return full.substr(full.find('.') + 1); }

TEST(SpyIntegrationTest, OnceListsEveryChannelWithItsDecodedType) {
  ProcessSet procs(PrivateLcmUrl());
  // Publishes every type for ~10 s; cairn-spy listens for 2 s in the middle.
  ChildProcess& publisher = procs.StartRaw(
      "publish_samples",
      {std::string(CAIRN_BINARY_DIR) + "/tests/publish_samples", procs.url(), "200"});
  ChildProcess& spy = procs.Start("cairn-spy", {"--once", "--duration", "2"});
  ASSERT_TRUE(spy.WaitExit(30.0).has_value());
  const std::string table = spy.Log();
  for (const auto& t : cairn::AllLcmTypes()) {
    const std::string row =
        "SAMPLE." + ShortName(t.name) + R"(\s+)" + std::string(t.name) + R"(\s+[0-9.]+)";
    EXPECT_TRUE(std::regex_search(table, std::regex(row))) << "no row for " << t.name << "\n"
                                                           << table;
  }
  publisher.Stop();
}

TEST(SpyIntegrationTest, JarHasEveryTypeAndJavaDecodesARecordedLog) {
  const std::string jar = std::string(CAIRN_BINARY_DIR) + "/share/java/cairn_lcmtypes.jar";
  ASSERT_TRUE(std::ifstream(jar).good()) << jar;
  ProcessSet procs(PrivateLcmUrl());

  // One class per .lcm file in the jar.
  ChildProcess& list = procs.StartRaw("jar", {"/usr/bin/jar", "tf", jar});
  ASSERT_TRUE(list.WaitExit(60.0).has_value());
  std::set<std::string> classes;
  std::regex class_re(R"(cairn/(lcmt_\w+)\.class)");
  const std::string listing = list.Log();
  for (std::sregex_iterator it(listing.begin(), listing.end(), class_re), end; it != end; ++it) {
    classes.insert((*it)[1]);
  }
  std::stringstream files(CAIRN_LCM_FILES);
  std::string file;
  int expected = 0;
  while (std::getline(files, file, ',')) {
    ++expected;
    const std::string type = file.substr(0, file.find('.'));
    EXPECT_TRUE(classes.count(type)) << "the jar has no class for " << type;
  }
  EXPECT_EQ(expected, static_cast<int>(cairn::AllLcmTypes().size()));

  // Record every type with lcm-logger, then decode the log in Java.
  const std::string log = procs.dir() + "/samples.lcmlog";
  ChildProcess& logger =
      procs.StartRaw("lcm-logger", {"/usr/bin/lcm-logger", "-f", "--lcm-url=" + procs.url(), log});
  Bus bus(procs.url());
  ChildProcess& publisher =
      procs.StartRaw("publish_samples",
                     {std::string(CAIRN_BINARY_DIR) + "/tests/publish_samples", procs.url(), "40"});
  // Wait until the publisher is done and our own subscriber saw every sample.
  ASSERT_TRUE(WaitFor([&] { return !publisher.Running(); }, 60.0, [&] { bus.Pump(20); }));
  std::string missing;  // the types not seen yet, for the failure message
  ASSERT_TRUE(WaitFor(
      [&] {
        missing.clear();
        for (const auto& t : cairn::AllLcmTypes()) {
          if (bus.Count("SAMPLE." + ShortName(t.name)) < 1) missing += " " + ShortName(t.name);
        }
        return missing.empty();
      },
      10.0, [&] { bus.Pump(20); }))
      << "never seen:" << missing;
  logger.Signal(SIGINT);
  ASSERT_TRUE(logger.WaitExit(10.0).has_value());

  ChildProcess& java = procs.StartRaw("java", {"/usr/bin/java", "-cp",
                                               "/usr/share/java/lcm.jar:" + jar + ":" +
                                                   std::string(CAIRN_BINARY_DIR) + "/tests/java",
                                               "DecodeLog", jar, log});
  auto exit = java.WaitExit(120.0);
  ASSERT_TRUE(exit.has_value());
  const std::string out = java.Log();
  EXPECT_TRUE(WIFEXITED(*exit) && WEXITSTATUS(*exit) == 0) << out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(decoded (\d+) failed 0 classes (\d+))")))
      << out;
  EXPECT_GE(std::stoi(m[1]), static_cast<int>(cairn::AllLcmTypes().size()));
  EXPECT_EQ(std::stoi(m[2]), static_cast<int>(cairn::AllLcmTypes().size()));
}

}  // namespace
}  // namespace cairn::testing
