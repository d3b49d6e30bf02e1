#include "services/launch/commands.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "services/launch/status.h"

namespace cairn::launch {
namespace {

namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() {
    char tmpl[] = "/tmp/cairn_launch_commands_XXXXXX";
    path_ = mkdtemp(tmpl);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// A child that sleeps until killed, in its own process group (as the runner starts them).
pid_t StartSleeper() {
  const pid_t pid = fork();
  if (pid == 0) {
    setpgid(0, 0);
    execl("/bin/sleep", "sleep", "600", static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

// Waits (bounded) until the child has exited, reaps it and says whether it did.
bool Reaped(pid_t pid, double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

TEST(ProcessAliveTest, ARunningProcessIsAliveAZombieAndAReapedOneAreNot) {
  EXPECT_TRUE(ProcessAlive(getpid()));
  EXPECT_FALSE(ProcessAlive(-1));
  EXPECT_FALSE(ProcessAlive(0));
  const pid_t child = fork();
  if (child == 0) _exit(0);
  // Until it is reaped the child is a zombie: gone for ProcessAlive.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (ProcessAlive(child) && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_FALSE(ProcessAlive(child));
  EXPECT_EQ(kill(child, 0), 0) << "the child should still be a zombie";
  ASSERT_TRUE(Reaped(child, 10.0));
  EXPECT_FALSE(ProcessAlive(child));
}

TEST(RunDirForTest, TheFlagWinsThenTheArgumentsStem) {
  EXPECT_EQ(RunDirFor("anything", "/tmp/run_here", {}), "/tmp/run_here");
  EXPECT_EQ(RunDirFor("/nonexistent/graphs/mission.yaml", "", {}), "var/run/mission");
}

TEST(SearchDirsTest, TheExecutablesFolderComesFirstThenThePathList) {
  const auto dirs = SearchDirs("/usr/local/bin::/usr/bin");
  ASSERT_EQ(dirs.size(), 3u);
  EXPECT_EQ(dirs[1], "/usr/local/bin");
  EXPECT_EQ(dirs[2], "/usr/bin");
  EXPECT_EQ(SearchDirs("").size(), 1u);
}

TEST(CmdStatusTest, AMissingStatusFileIsAnError) {
  TempDir dir;
  EXPECT_EQ(CmdStatus(dir.path()), 1);
}

TEST(CmdWaitTest, AGraphWhoseLauncherIsGoneIsNotWaitedFor) {
  TempDir dir;
  GraphStatus status;
  status.graph = "g";
  status.state = "starting";
  const pid_t child = fork();
  if (child == 0) _exit(0);
  ASSERT_TRUE(Reaped(child, 10.0));
  status.launcher_pid = child;  // exited and reaped: not running
  ASSERT_TRUE(WriteStatusFile(dir.path() + "/status.json", status));
  EXPECT_EQ(CmdWait(dir.path(), 30.0), 1);
}

TEST(CmdWaitTest, NoStatusFileTimesOut) {
  TempDir dir;
  EXPECT_EQ(CmdWait(dir.path(), 0.2), 2);
}

TEST(CmdDownTest, WithoutALauncherTheListedProcessesAreKilled) {
  TempDir dir;
  const pid_t orphan = StartSleeper();
  ASSERT_GT(orphan, 0);
  GraphStatus status;
  status.graph = "g";
  status.state = "ready";
  status.launcher_pid = -1;
  ProcessRow row;
  row.name = "sleeper";
  row.pid = orphan;
  status.processes.push_back(row);
  ASSERT_TRUE(WriteStatusFile(dir.path() + "/status.json", status));
  EXPECT_EQ(CmdDown(dir.path(), 5.0), 0);
  EXPECT_TRUE(Reaped(orphan, 10.0)) << "the orphan was not killed";
}

TEST(CmdDownTest, ALauncherThatStopsOnSigtermIsWaitedFor) {
  TempDir dir;
  const pid_t launcher = StartSleeper();  // sleep ends on SIGTERM
  std::ofstream(dir.path() + "/launch.pid") << launcher << "\n";
  // Reap it in the background so that it does not linger as a zombie.
  std::thread reaper([&] { EXPECT_TRUE(Reaped(launcher, 30.0)); });
  EXPECT_EQ(CmdDown(dir.path(), 20.0), 0);
  reaper.join();
}

TEST(CmdCheckTest, AnInvalidGraphIsRefused) {
  TempDir dir;
  const std::string path = dir.path() + "/cycle.yaml";
  std::ofstream(path) << "processes:\n  a:\n    command: /bin/true\n    depends_on: [b]\n"
                      << "  b:\n    command: /bin/true\n    depends_on: [a]\n";
  EXPECT_EQ(CmdCheck(path, {"/bin"}), 2);
  const std::string good = dir.path() + "/good.yaml";
  std::ofstream(good) << "processes:\n  a:\n    command: /bin/true\n    ready: {heartbeat: false}\n";
  EXPECT_EQ(CmdCheck(good, {"/bin"}), 0);
  std::ofstream(good, std::ios::trunc) << "processes:\n  a:\n    command: true\n"
                                        << "    ready: {heartbeat: false}\n";
  EXPECT_EQ(CmdCheck(good, {}), 2) << "a bare name is looked up in the search folders only";
  EXPECT_EQ(CmdCheck(good, {"/nonexistent", "/bin"}), 0);
}

TEST(PrepareUpTest, MakesTheRunDirAndPidFileAndRefusesASecondLauncher) {
  TempDir dir;
  const std::string graph = dir.path() + "/g.yaml";
  std::ofstream(graph) << "name: g\nprocesses:\n  a:\n    command: /bin/true\n"
                       << "    ready: {heartbeat: false}\n";
  const std::string run_dir = dir.path() + "/run";
  int code = -1;
  auto plan = PrepareUp(graph, "memq://", run_dir, /*detach=*/false, {}, &code);
  ASSERT_TRUE(plan.has_value());
  EXPECT_EQ(code, 0);
  EXPECT_EQ(plan->lcm_url, "memq://");
  EXPECT_TRUE(fs::is_directory(run_dir + "/logs"));
  int pid = -1;
  std::ifstream(run_dir + "/launch.pid") >> pid;
  EXPECT_EQ(pid, getpid());
  // Another launcher (alive) holds the run directory: refused.
  const pid_t other = StartSleeper();
  std::ofstream(run_dir + "/launch.pid", std::ios::trunc) << other << "\n";
  EXPECT_FALSE(PrepareUp(graph, "", run_dir, false, {}, &code).has_value());
  EXPECT_EQ(code, 2);
  kill(other, SIGKILL);
  EXPECT_TRUE(Reaped(other, 10.0));
  FinishUp(*plan);
  EXPECT_FALSE(fs::exists(run_dir + "/launch.pid"));
}

}  // namespace
}  // namespace cairn::launch
