/// @file launcher_death_test.cc
/// @brief `kill -9` of `p2i launch`: every node notices at once (PR_SET_PDEATHSIG), shuts down
/// cleanly although its output pipes are gone (SIGPIPE ignored: exit code 0, slam_sink writes
/// summary.json, registry entries removed); the next launch removes the dead launch's run dir
/// and parameter folder; an unknown parameter names the launch file and line.
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>

#include "tests/read_file.h"
#include "tests/test_paths.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

using p2i::testing::ReadFile;

namespace {

// `p2i launch ARGS` with stdout+stderr to `log`, P2I_RUN_DIR unset (the launcher makes its own).
pid_t StartLaunch(const std::vector<std::string>& args, const std::string& log) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::unsetenv("P2I_RUN_DIR");
    FILE* f = std::fopen(log.c_str(), "w");
    if (f == nullptr) ::_exit(126);
    ::dup2(fileno(f), 1);
    ::dup2(fileno(f), 2);
    std::vector<std::string> all = {p2i::testing::BinDir() + "/p2i", "launch"};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

// Waits (safety limit, not a timing assertion) until `cond`.
bool WaitUntil(const std::function<bool()>& cond, double limit_s) {
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(limit_s));
  while (Clock::now() < end) {
    if (cond()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return cond();
}

}  // namespace

// long-function: one scenario: a launch killed with -9, its orphaned nodes reaped, then
// the next launch cleaning up what the killed one left; each step needs the previous one's state.
TEST_CASE("kill -9 of p2i launch: nodes shut down cleanly at once, the next launch cleans up",
          "[integration]") {
  // Orphaned nodes are re-parented to this process, so it can reap them and see how they ended.
  REQUIRE(::prctl(PR_SET_CHILD_SUBREAPER, 1) == 0);
  const fs::path dir = fs::temp_directory_path() / ("p2i_launcher_death_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string out = (dir / "sink").string();
  const std::string file = (dir / "graph.yaml").string();
  std::ofstream(file) << "launch:\n"
                         "- arg: {name: out}\n"
                         "- node:\n"
                         "    exec: pose_source\n"
                         "    name: poses\n"
                         "    param:\n"
                         "    - {name: rate, value: 50.0}\n"
                         "    - {name: log_level, value: debug}\n"
                         "- node:\n"
                         "    exec: slam_sink\n"
                         "    name: sink\n"
                         "    param:\n"
                         "    - {name: out_dir, value: \"$(var out)\"}\n"
                         "    - {name: summary_period, value: 0.0}\n"
                         "    - {name: check, value: false}\n";
  const std::string log1 = (dir / "launch1.log").string();
  const pid_t launcher = StartLaunch({file, "out:=" + out}, log1);
  REQUIRE(launcher > 0);

  // The run dir the launcher chose, and both nodes' registry entries (they are up).
  std::string run_dir;
  std::map<std::string, pid_t> node_pids;  // node -> pid
  const bool up = WaitUntil([&] {
    std::smatch m;
    const std::string text = ReadFile(log1);
    if (run_dir.empty() && std::regex_search(text, m, std::regex("P2I_RUN_DIR=(\\S+)")))
      run_dir = m[1];
    if (run_dir.empty() || !fs::exists(run_dir + "/registry")) return false;
    for (const auto& e : fs::directory_iterator(run_dir + "/registry")) {
      const std::string name = e.path().filename().string();
      const auto dot = name.find('.');
      if (name.find("status") == std::string::npos) continue;
      node_pids[name.find("sink") != std::string::npos ? "sink" : "poses"] =
          std::stoi(name.substr(0, dot));
    }
    return node_pids.size() == 2;
  }, 30.0);
  INFO(ReadFile(log1));
  REQUIRE(up);
  std::string params_dir;
  for (const auto& e : fs::directory_iterator("/tmp")) {
    const std::string n = e.path().filename().string();
    if (n.rfind("p2i-launch-params-" + std::to_string(launcher) + "-", 0) == 0) params_dir = e.path();
  }
  CHECK_FALSE(params_dir.empty());

  const auto t0 = Clock::now();
  REQUIRE(::kill(launcher, SIGKILL) == 0);
  int status = 0;
  REQUIRE(::waitpid(launcher, &status, 0) == launcher);
  // Reap the orphans: each must have exited by itself with code 0 (not killed by SIGPIPE).
  std::map<pid_t, int> ended;
  const bool all_gone = WaitUntil([&] {
    int st = 0;
    pid_t p;
    while ((p = ::waitpid(-1, &st, WNOHANG)) > 0) ended[p] = st;
    return ended.size() >= node_pids.size();
  }, 20.0);
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  WARN("nodes gone " << seconds << " s after kill -9 of the launcher");  // a figure, not asserted
  REQUIRE(all_gone);
  for (const auto& [node, pid] : node_pids) {
    INFO(node);
    REQUIRE(ended.count(pid) == 1);
    CHECK(WIFEXITED(ended[pid]));
    if (WIFSIGNALED(ended[pid])) CHECK(WTERMSIG(ended[pid]) == 0);  // shows the signal
    if (WIFEXITED(ended[pid])) CHECK(WEXITSTATUS(ended[pid]) == 0);
  }
  CHECK(fs::exists(out + "/summary.json"));                // OnShutdown ran
  CHECK(fs::is_empty(run_dir + "/registry"));              // every endpoint unregistered
  CHECK(fs::exists(run_dir));                              // nobody removed it (yet)
  CHECK(fs::exists(params_dir));

  // The next launch removes both; its node's unknown parameter names the launch file's line.
  const std::string bad = (dir / "bad.yaml").string();
  std::ofstream(bad) << "launch:\n"
                        "- node:\n"
                        "    exec: slam_sink\n"
                        "    param:\n"
                        "    - {name: out_dir, value: \"" << dir.string() << "/sink2\"}\n"
                        "    - {name: zz, value: 1}\n";
  const std::string log2 = (dir / "launch2.log").string();
  const pid_t second = StartLaunch({bad}, log2);
  REQUIRE(::waitpid(second, &status, 0) == second);
  const std::string text = ReadFile(log2);
  INFO(text);
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 1);  // a node failed
  // Both are gone after the next launch. Which launch removed them is not asserted: under
  // `ctest -j2` another test's `p2i launch` may start in between and sweep them first (every
  // launch removes every dead launcher's folders). The sweep's rules (dead pids only, this
  // user's folders only, the removed paths returned for the "[launch] removed" report) are
  // pinned without that race by tests/tools/launch_cleanup_test.cc on folders of its own.
  CHECK_FALSE(fs::exists(run_dir));
  CHECK_FALSE(fs::exists(params_dir));
  CHECK_THAT(text, Catch::Contains("unknown parameter 'zz' (from " + bad + ":6"));
  CHECK_THAT(text, Catch::Contains("exited with code 2"));
  CHECK_FALSE(fs::exists(dir.string() + "/sink2"));  // validated before creating anything
  ::prctl(PR_SET_CHILD_SUBREAPER, 0);
  fs::remove_all(dir);
}
