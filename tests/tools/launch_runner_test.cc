/// @file launch_runner_test.cc
/// @brief `p2i launch` end to end: real processes (p2i_fake_node), output prefixes, respawn,
/// required nodes, SIGTERM of the launcher, exit codes, --dry-run.
#include <dirent.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>

#include "tests/read_file.h"
#include "tests/temp_dir.h"
#include "tests/test_paths.h"

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

using p2i::testing::TempDir;

// `p2i launch ...` as a child process with stdout and stderr captured.
class Launcher {
 public:
  explicit Launcher(std::vector<std::string> args) {
    const std::string p2i = p2i::testing::BinDir() + "/p2i";
    REQUIRE(fs::exists(p2i));
    args.insert(args.begin(), {p2i, "launch"});
    int out[2], err[2];
    REQUIRE(::pipe2(out, O_CLOEXEC) == 0);
    REQUIRE(::pipe2(err, O_CLOEXEC) == 0);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_ = ::fork();
    REQUIRE(pid_ >= 0);
    if (pid_ == 0) {
      ::dup2(out[1], 1);
      ::dup2(err[1], 2);
      ::unsetenv("P2I_RUN_DIR");
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    ::close(out[1]);
    ::close(err[1]);
    out_fd_ = out[0];
    err_fd_ = err[0];
  }
  ~Launcher() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (out_fd_ >= 0) ::close(out_fd_);
    if (err_fd_ >= 0) ::close(err_fd_);
  }

  pid_t pid() const { return pid_; }

  /// Reads all output until the launcher exits; returns its exit code (-1 after `limit`,
  /// a safety net against a hung test, not a timing assertion).
  int Wait(double limit_s = 60.0) {
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(limit_s));
    while (out_fd_ >= 0 || err_fd_ >= 0) {
      if (Clock::now() > deadline) return -1;
      std::vector<pollfd> fds;
      if (out_fd_ >= 0) fds.push_back({out_fd_, POLLIN, 0});
      if (err_fd_ >= 0) fds.push_back({err_fd_, POLLIN, 0});
      ::poll(fds.data(), fds.size(), 100);
      for (const auto& f : fds) {
        if (f.revents == 0) continue;
        char buf[4096];
        const ssize_t n = ::read(f.fd, buf, sizeof(buf));
        std::string& sink = f.fd == out_fd_ ? out_ : err_;
        if (n > 0) {
          sink.append(buf, static_cast<size_t>(n));
        } else {
          ::close(f.fd);
          (f.fd == out_fd_ ? out_fd_ : err_fd_) = -1;
        }
      }
    }
    int status = 0;
    while (true) {
      const pid_t r = ::waitpid(pid_, &status, WNOHANG);
      if (r == pid_) break;
      if (Clock::now() > deadline) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

  const std::string& out() const { return out_; }
  const std::string& err() const { return err_; }

 private:
  pid_t pid_ = -1;
  int out_fd_ = -1, err_fd_ = -1;
  std::string out_, err_;
};

std::vector<pid_t> PidsIn(const std::string& dir) {
  std::vector<pid_t> pids;
  for (const auto& e : fs::directory_iterator(dir)) pids.push_back(std::stoi(e.path().filename()));
  return pids;
}

bool Alive(pid_t pid) { return ::kill(pid, 0) == 0 || errno != ESRCH; }

int CountLines(const std::string& path) {
  std::ifstream in(path);
  int n = 0;
  std::string l;
  while (std::getline(in, l)) ++n;
  return n;
}

}  // namespace

TEST_CASE("p2i launch prefixes node output and passes the contract command line",
          "[integration]") {
  TempDir dir;
  const std::string file = dir.Write("two.yaml", R"(launch:
- arg: {name: lines, default: "2"}
- group:
  - push-ros-namespace: {namespace: robot}
  - node:
      exec: fake_node
      name: alpha
      param:
      - {name: rate, value: "30"}
      - {name: size, value: [64, 64]}
      remap:
      - {from: rgbd, to: /cam/rgbd}
      args: "--lines $(var lines) --print-env P2I_RUN_DIR"
- node:
    exec: fake_node
    name: beta
    args: "--lines 1 --print-env P2I_RUN_DIR"
)");
  Launcher launcher({file, "lines:=3"});
  REQUIRE(launcher.Wait() == 0);
  const std::string& out = launcher.out();
  INFO(out << launcher.err());
  CHECK_THAT(out, Catch::Contains("[alpha] line 0\n"));
  CHECK_THAT(out, Catch::Contains("[alpha] line 2\n"));
  CHECK_THAT(out, !Catch::Contains("[alpha] line 3\n"));
  CHECK_THAT(out, Catch::Contains("[beta] line 0\n"));
  // Each inline parameter carries its launch file line (the node's errors name it).
  CHECK_THAT(out, Catch::Contains("[alpha] param rate: 30  #@ "));
  CHECK_THAT(out, Catch::Contains("two.yaml:9\n"));
  CHECK_THAT(out, Catch::Contains("[alpha] param size: [64, 64]  #@ "));
  CHECK_THAT(out, Catch::Contains("two.yaml:10\n"));
  CHECK_THAT(out, Catch::Contains("--name alpha --namespace /robot --params-file "));
  CHECK_THAT(out, Catch::Contains("-r rgbd:=/cam/rgbd --lines 3"));
  CHECK_THAT(launcher.err(), Catch::Contains("[alpha] done"));  // stderr is prefixed too
  // Every line of the nodes carries a prefix.
  std::istringstream lines(out);
  std::string line;
  while (std::getline(lines, line)) {
    CHECK((line.rfind("[alpha] ", 0) == 0 || line.rfind("[beta] ", 0) == 0));
  }
  // Both nodes see the same, non-default run dir.
  const auto run_dir_of = [&](const std::string& node) {
    const std::string key = "[" + node + "] P2I_RUN_DIR=";
    const auto pos = out.find(key);
    REQUIRE(pos != std::string::npos);
    return out.substr(pos + key.size(), out.find('\n', pos) - pos - key.size());
  };
  CHECK(run_dir_of("alpha") == run_dir_of("beta"));
  CHECK(run_dir_of("alpha") != "(unset)");
  CHECK_FALSE(fs::exists(run_dir_of("alpha")));  // the launcher's own run dir is cleaned up
}

TEST_CASE("p2i launch gives the nodes OMP_WAIT_POLICY=PASSIVE unless the user set one",
          "[integration]") {
  TempDir dir;
  const std::string file = dir.Write("one.yaml", R"(launch:
- node: {exec: fake_node, name: alpha, args: "--lines 0 --print-env OMP_WAIT_POLICY"}
)");
  const char* before = std::getenv("OMP_WAIT_POLICY");
  const std::string saved = before != nullptr ? before : "";
  const auto policy_seen = [&](const char* value) {
    if (value == nullptr) {
      ::unsetenv("OMP_WAIT_POLICY");
    } else {
      ::setenv("OMP_WAIT_POLICY", value, 1);
    }
    Launcher launcher({file});
    REQUIRE(launcher.Wait() == 0);
    const std::string key = "[alpha] OMP_WAIT_POLICY=";
    const auto pos = launcher.out().find(key);
    REQUIRE(pos != std::string::npos);
    return launcher.out().substr(pos + key.size(),
                                 launcher.out().find('\n', pos) - pos - key.size());
  };
  CHECK(policy_seen(nullptr) == "PASSIVE");
  CHECK(policy_seen("active") == "active");  // the user's choice wins
  if (before != nullptr) {
    ::setenv("OMP_WAIT_POLICY", saved.c_str(), 1);
  } else {
    ::unsetenv("OMP_WAIT_POLICY");
  }
}

TEST_CASE("p2i launch respawns respawn nodes until a required node exits", "[integration]") {
  TempDir dir;
  const std::string starts = dir.path() + "/starts.txt";
  const std::string file = dir.Write("respawn.yaml", R"(launch:
- node:
    exec: fake_node
    name: flaky
    respawn: true
    respawn_delay: 0.05
    args: "--start-file )" + starts + R"("
- node:
    exec: fake_node
    name: main
    required: true
    args: "--sleep 1.5"
- node:
    exec: fake_node
    name: bystander
    args: "--forever"
)");
  Launcher launcher({file});
  REQUIRE(launcher.Wait() == 0);
  INFO(launcher.out() << launcher.err());
  CHECK(CountLines(starts) >= 2);
  CHECK_THAT(launcher.err(), Catch::Contains("[flaky] respawning in 0.05 s"));
  CHECK_THAT(launcher.err(), Catch::Contains("required node 'main' exited"));
  CHECK_THAT(launcher.out(), Catch::Contains("[bystander] got SIGTERM"));
}

TEST_CASE("p2i launch exits non-zero when a node fails", "[integration]") {
  TempDir dir;
  SECTION("non-zero exit code") {
    const std::string file = dir.Write("fail.yaml", R"(launch:
- node: {exec: fake_node, name: ok}
- node: {exec: fake_node, name: bad, args: "--exit-code 3"}
)");
    Launcher launcher({file});
    CHECK(launcher.Wait() == 1);
    CHECK_THAT(launcher.err(), Catch::Contains("[bad] exited with code 3 -- FAILED"));
    CHECK_THAT(launcher.err(), Catch::Contains("[ok] exited cleanly"));
  }
  SECTION("crash") {
    const std::string file =
        dir.Write("crash.yaml", "launch:\n- node: {exec: fake_node, name: c, args: --crash}\n");
    Launcher launcher({file});
    CHECK(launcher.Wait() == 1);
    CHECK_THAT(launcher.err(), Catch::Contains("[c] killed by signal 11"));
  }
  SECTION("all clean") {
    const std::string file =
        dir.Write("ok.yaml", "launch:\n- node: {exec: fake_node, name: a}\n");
    Launcher launcher({file});
    CHECK(launcher.Wait() == 0);
  }
  SECTION("unknown executable: nothing starts") {
    const std::string file = dir.Write(
        "missing.yaml",
        "launch:\n- node: {exec: fake_node, name: a, args: --lines 1}\n- node: {exec: nope_xyz}\n");
    Launcher launcher({file});
    CHECK(launcher.Wait() == 2);  // configuration error (exit code rule, docs/RUNTIME.md)
    CHECK_THAT(launcher.err(), Catch::Contains("missing.yaml:3"));
    CHECK_THAT(launcher.err(), Catch::Contains("nope_xyz"));
    CHECK_THAT(launcher.out(), !Catch::Contains("[a] line 0"));
  }
}

TEST_CASE("SIGTERM to p2i launch stops every node, SIGKILL after the grace period",
          "[integration]") {
  TempDir dir;
  const std::string pids = dir.path() + "/pids";
  fs::create_directories(pids);
  const std::string file = dir.Write("stop.yaml", R"(launch:
- node: {exec: fake_node, name: polite, args: "--forever --pid-dir )" + pids + R"("}
- node: {exec: fake_node, name: stubborn, args: "--forever --ignore-sigterm --pid-dir )" +
                                                  pids + R"("}
)");
  Launcher launcher({file, "--grace-period", "1"});
  const auto deadline = Clock::now() + std::chrono::seconds(30);
  while (PidsIn(pids).size() < 2 && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const std::vector<pid_t> children = PidsIn(pids);
  REQUIRE(children.size() == 2);
  for (pid_t p : children) CHECK(Alive(p));
  ::kill(launcher.pid(), SIGTERM);
  const int code = launcher.Wait();
  INFO(launcher.out() << launcher.err());
  CHECK(code == 0);  // both were stopped by the launcher itself: no failure
  for (pid_t p : children) CHECK_FALSE(Alive(p));
  CHECK_THAT(launcher.out(), Catch::Contains("[polite] got SIGTERM"));
  CHECK_THAT(launcher.err(), Catch::Contains("grace period of 1 s over"));
  CHECK_THAT(launcher.err(), Catch::Contains("[stubborn] did not stop: SIGKILL"));
}

TEST_CASE("p2i launch --dry-run prints command lines and starts nothing", "[integration]") {
  TempDir dir;
  const std::string pids = dir.path() + "/pids";
  fs::create_directories(pids);
  const std::string file = dir.Write("dry.yaml", R"(launch:
- arg: {name: ns, default: "r"}
- node:
    exec: fake_node
    name: n1
    namespace: $(var ns)
    param: [{name: rate, value: "7"}]
    args: "--pid-dir )" + pids + R"("
)");
  Launcher launcher({file, "--dry-run", "ns:=robot2"});
  REQUIRE(launcher.Wait() == 0);
  const std::string& out = launcher.out();
  INFO(out << launcher.err());
  CHECK_THAT(out, Catch::Contains(p2i::testing::BinDir() + "/p2i_fake_node --name n1 "
                                  "--namespace /robot2 --params-file "));
  CHECK_THAT(out, Catch::Contains("#     rate: 7"));
  CHECK_THAT(out, Catch::Contains("dry.yaml:3"));
  CHECK(PidsIn(pids).empty());
  // The kept parameter folder is named in the output; clean it up.
  const auto pos = out.find("kept in ");
  REQUIRE(pos != std::string::npos);
  fs::remove_all(out.substr(pos + 8, out.find('\n', pos) - pos - 8));
}

TEST_CASE("p2i launch output: log writes to <log-dir>/<name>.log only", "[integration]") {
  TempDir dir;
  const std::string logs = dir.path() + "/logs";
  const std::string file = dir.Write("log.yaml", R"(launch:
- node: {exec: fake_node, name: quiet, output: log, args: "--lines 2"}
- node: {exec: fake_node, name: chatty, output: both, args: "--lines 1"}
)");
  Launcher launcher({file, "--log-dir", logs});
  REQUIRE(launcher.Wait() == 0);
  INFO(launcher.out() << launcher.err());
  CHECK_THAT(launcher.out(), !Catch::Contains("[quiet]"));
  CHECK_THAT(launcher.out(), Catch::Contains("[chatty] line 0"));
  const std::string text = p2i::testing::ReadFile(logs + "/quiet.log");
  CHECK_THAT(text, Catch::Contains("line 1\n"));
  CHECK_THAT(text, Catch::Contains("done\n"));  // stderr goes to the log too
  CHECK(CountLines(logs + "/chatty.log") >= 2);
}
