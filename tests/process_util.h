/// @file process_util.h
/// @brief Child processes for tests that run nodes and tools as a user would.
#pragma once

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <stdexcept>
#include <string>
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

}  // namespace p2i::testing
