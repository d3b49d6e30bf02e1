#include "services/launch/posix_runner.h"

#include <fcntl.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace cairn::launch {
namespace {

namespace fs = std::filesystem;

std::string Read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class RotateLogTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("cairn_rotate_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    path_ = (dir_ / "p.log").string();
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
  std::string path_;
};

// Issue 20: a process's log grew without limit. Rotated at the size limit, keeping `keep`
// copies, while the writer (O_APPEND, as the launcher's children write) goes on writing to the
// same file from its start.
TEST_F(RotateLogTest, RotatesAtTheLimitKeepsNCopiesAndTheWriterGoesOn) {
  const int fd = open(path_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  ASSERT_GE(fd, 0);
  auto write_text = [&](const std::string& text) {
    ASSERT_EQ(write(fd, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  };
  std::string error;
  write_text(std::string(100, 'a'));
  EXPECT_FALSE(RotateLog(path_, 100, 2, &error).has_value());  // at the limit: kept
  EXPECT_TRUE(error.empty());
  for (char c : {'b', 'c', 'd'}) {
    write_text(std::string(1, c));
    const auto rotated = RotateLog(path_, 100, 2, &error);
    ASSERT_TRUE(rotated.has_value()) << error;
    EXPECT_EQ(fs::file_size(path_), 0u);
    write_text(std::string(150, c));  // the same descriptor writes at the new end
  }
  close(fd);
  EXPECT_EQ(Read(path_), std::string(150, 'd'));
  EXPECT_EQ(Read(path_ + ".1"), std::string(150, 'c') + "d");
  EXPECT_EQ(Read(path_ + ".2"), std::string(150, 'b') + "c");
  EXPECT_FALSE(fs::exists(path_ + ".3"));  // the oldest copy was dropped
}

TEST_F(RotateLogTest, AMissingLogIsNothingAndAFailureLeavesTheLogAsItWas) {
  std::string error;
  EXPECT_FALSE(RotateLog((dir_ / "none.log").string(), 10, 3, &error).has_value());
  EXPECT_TRUE(error.empty());
  std::ofstream(path_) << std::string(50, 'x');
  fs::create_directories(path_ + ".1/in-the-way");  // a folder where the copy goes
  EXPECT_FALSE(RotateLog(path_, 10, 1, &error).has_value());
  EXPECT_NE(error.find("p.log.1"), std::string::npos) << error;
  EXPECT_EQ(Read(path_), std::string(50, 'x'));
}

}  // namespace
}  // namespace cairn::launch
