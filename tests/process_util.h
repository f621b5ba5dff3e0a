/// @file process_util.h
/// @brief Child processes for tests that run nodes and tools as a user would.
#pragma once

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace p2i::testing {

/// A child process started with posix_spawn (inheriting the environment, e.g. P2I_RUN_DIR);
/// SIGTERM + wait on destruction if still running. Thread-compatible.
class Process {
 public:
  explicit Process(std::vector<std::string> argv) {
    std::vector<char*> args;
    for (std::string& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    if (posix_spawn(&pid_, args[0], nullptr, nullptr, args.data(), environ) != 0) pid_ = -1;
  }
  ~Process() {
    if (pid_ > 0) Terminate();
  }
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  /// SIGTERM, then the exit code (or -signal).
  int Terminate() {
    if (pid_ <= 0) return -1000;
    kill(pid_, SIGTERM);
    return Wait();
  }
  /// Waits for the process to exit by itself; its exit code (or -signal).
  int Wait() {
    if (pid_ <= 0) return -1000;
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
  }
  bool Running() const { return pid_ > 0 && kill(pid_, 0) == 0; }
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
};

/// `BIN_DIR/p2i launch ARGS...` as a child with stdout + stderr in `log`, P2I_RUN_DIR as given
/// ("" = unset: the launcher makes /tmp/p2i-$UID/launch-<pid>, found by discovery without
/// exports), P2I_CURVE_DIR and P2I_PEERS unset. Stop it with StopLaunch().
inline pid_t StartLaunch(const std::string& bin_dir, const std::vector<std::string>& args,
                         const std::string& run_dir, const std::string& log) {
  const pid_t pid = fork();
  if (pid == 0) {
    if (run_dir.empty()) unsetenv("P2I_RUN_DIR"); else setenv("P2I_RUN_DIR", run_dir.c_str(), 1);
    unsetenv("P2I_CURVE_DIR");
    unsetenv("P2I_PEERS");
    if (!freopen(log.c_str(), "w", stdout)) _exit(126);
    dup2(fileno(stdout), 2);
    const std::string exe = bin_dir + "/p2i";
    std::vector<char*> argv = {const_cast<char*>(exe.c_str()), const_cast<char*>("launch")};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(exe.c_str(), argv.data());
    _exit(127);
  }
  return pid;
}

/// SIGINT to a launcher (it stops its nodes) and its exit code (128 + signal if killed).
inline int StopLaunch(pid_t pid) {
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// Runs a shell command; returns its stdout and sets `*exit_code` (-1 if it did not exit).
inline std::string RunCommand(const std::string& command, int* exit_code) {
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("popen failed: " + command);
  std::string out;
  std::array<char, 4096> buf{};
  size_t n = 0;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) out.append(buf.data(), n);
  const int status = pclose(pipe);
  *exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return out;
}

/// Runs `command` every 200 ms until its stdout contains `needle` or `seconds` pass; the last
/// output.
inline std::string RunCommandUntil(const std::string& command, const std::string& needle,
                                   int seconds = 20) {
  std::string out;
  int code = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  while (std::chrono::steady_clock::now() < deadline) {
    out = RunCommand(command, &code);
    if (out.find(needle) != std::string::npos) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  return out;
}

}  // namespace p2i::testing
