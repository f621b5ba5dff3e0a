/// @file launch_cleanup_test.cc
/// @brief The stale-folder sweep of `p2i launch` (tools/launch_cleanup.h) on folders of its own,
/// so no other launch running in parallel can sweep them first.
#include "tools/launch_cleanup.h"

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/temp_dir.h"

namespace fs = std::filesystem;

namespace {

// The pid of a process that has exited and been reaped (so it names no running process).
pid_t DeadPid() {
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(0);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return pid;
}

bool Has(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

}  // namespace

TEST_CASE("launch clean-up removes the folders of dead launchers only", "[unit]") {
  p2i::testing::TempDir root("launch_root");
  p2i::testing::TempDir tmp("launch_tmp");
  const std::string dead = std::to_string(DeadPid());
  const std::string alive = std::to_string(::getppid());  // the test runner's parent is running
  const std::string mine = std::to_string(::getpid());
  for (const std::string& d : std::vector<std::string>{"launch-" + dead, "launch-" + alive,
                                                       "launch-" + mine, "launch-abc", "log",
                                                       "other-" + dead})
    fs::create_directories(root / d + "/registry");
  for (const std::string& d : std::vector<std::string>{"p2i-launch-params-" + dead + "-Ab12Cd",
                                                       "p2i-launch-params-" + alive + "-Xy34Zw",
                                                       "p2i-other-" + dead})
    fs::create_directories(tmp / d);
  // A plain file with a dead launcher's name is not a folder this sweep made.
  const std::string file = tmp / ("p2i-launch-params-" + dead + "-file");
  tmp.Write("p2i-launch-params-" + dead + "-file", "x");

  const auto removed = p2i::tools::RemoveStaleLaunchDirs(root.path(), tmp.path());

  CHECK(removed.size() == 2);
  CHECK(Has(removed, root / ("launch-" + dead)));
  CHECK(Has(removed, tmp / ("p2i-launch-params-" + dead + "-Ab12Cd")));
  CHECK_FALSE(fs::exists(root / ("launch-" + dead)));
  CHECK_FALSE(fs::exists(tmp / ("p2i-launch-params-" + dead + "-Ab12Cd")));
  // A running launcher, this process, names that are not a launch's, and plain files stay.
  CHECK(fs::exists(root / ("launch-" + alive)));
  CHECK(fs::exists(root / ("launch-" + mine)));
  CHECK(fs::exists(root / "launch-abc"));
  CHECK(fs::exists(root / "log"));
  CHECK(fs::exists(root / ("other-" + dead)));
  CHECK(fs::exists(tmp / ("p2i-launch-params-" + alive + "-Xy34Zw")));
  CHECK(fs::exists(tmp / ("p2i-other-" + dead)));
  CHECK(fs::exists(file));

  // A second sweep finds nothing left to remove.
  CHECK(p2i::tools::RemoveStaleLaunchDirs(root.path(), tmp.path()).empty());
}

TEST_CASE("launch clean-up of folders that do not exist removes nothing and does not throw",
          "[unit]") {
  CHECK(p2i::tools::RemoveStaleLaunchDirs("/nonexistent/p2i-root", "/nonexistent/tmp").empty());
}

TEST_CASE("a launch's parameter folder is new, private and named by its pid", "[unit]") {
  p2i::testing::TempDir tmp("launch_tmp");
  const std::string a = p2i::tools::MakeLaunchParamsDir(tmp.path());
  const std::string b = p2i::tools::MakeLaunchParamsDir(tmp.path());
  CHECK(a != b);
  CHECK(fs::path(a).filename().string().rfind(
            "p2i-launch-params-" + std::to_string(::getpid()) + "-", 0) == 0);
  struct stat st {};
  REQUIRE(::stat(a.c_str(), &st) == 0);
  CHECK((st.st_mode & 0777) == 0700);
  // This process is alive: its own folders are never swept.
  CHECK(p2i::tools::RemoveStaleLaunchDirs(tmp / "none", tmp.path()).empty());
  CHECK_THROWS(p2i::tools::MakeLaunchParamsDir("/nonexistent/tmp"));
}
