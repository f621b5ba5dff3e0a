/// @file bench_process.h
/// @brief What the benchmark programs that run p2i executables beside them share: a child
/// process with its own P2I_RUN_DIR (and optionally pinned to one CPU), stdout + stderr to a log
/// file, SIGTERM + wait on Stop() or destruction; the load average and a nearest-rank
/// percentile for their tables. Header-only: each bench is one .cc (bench/CMakeLists.txt).
#pragma once

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "util/order_stats.h"

extern char** environ;

namespace p2i::bench {

/// 1-minute load average (/proc/loadavg).
inline double LoadAverage() {
  std::ifstream in("/proc/loadavg");
  double l = 0;
  in >> l;
  return l;
}

/// Nearest-rank percentile, p in [0, 100] (as the monitor, util/order_stats.h); 0 for no values.
inline double Percentile(const std::vector<double>& v, double p) {
  return v.empty() ? 0.0 : util::PercentileNearestRank(v, p);
}

struct ChildOptions {
  std::string run_dir;  ///< P2I_RUN_DIR of the child ("" = inherit this process's)
  std::string log;      ///< stdout + stderr go here ("" = inherit)
  int cpu = -1;         ///< pin the child to this CPU (-1 = no pinning)
};

/// A child process started with posix_spawn (fork + exec when pinned to a CPU).
class Child {
 public:
  Child(std::vector<std::string> argv, const ChildOptions& o) {
    std::vector<std::string> env_store;
    for (char** e = environ; *e != nullptr; ++e)
      if (o.run_dir.empty() || std::strncmp(*e, "P2I_RUN_DIR=", 12) != 0) env_store.emplace_back(*e);
    if (!o.run_dir.empty()) env_store.push_back("P2I_RUN_DIR=" + o.run_dir);
    std::vector<char*> env, args;
    for (auto& e : env_store) env.push_back(e.data());
    env.push_back(nullptr);
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    if (o.cpu >= 0) {  // posix_spawn cannot set the affinity: fork, pin, exec
      pid_ = ::fork();
      if (pid_ == 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(o.cpu, &set);
        ::sched_setaffinity(0, sizeof set, &set);
        if (!o.log.empty()) {
          const int fd = ::open(o.log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
          if (fd >= 0) { ::dup2(fd, 1); ::dup2(fd, 2); ::close(fd); }
        }
        ::execve(args[0], args.data(), env.data());
        ::_exit(127);
      }
    } else {
      posix_spawn_file_actions_t fa;
      posix_spawn_file_actions_init(&fa);
      if (!o.log.empty()) {
        posix_spawn_file_actions_addopen(&fa, 1, o.log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        posix_spawn_file_actions_adddup2(&fa, 1, 2);
      }
      if (posix_spawn(&pid_, args[0], &fa, nullptr, args.data(), env.data()) != 0) pid_ = -1;
      posix_spawn_file_actions_destroy(&fa);
    }
    if (pid_ < 0) throw std::runtime_error("cannot start " + argv[0]);
  }
  /// The old signature of pipeline_bench / pool_bench: own run dir, log, no pinning.
  Child(std::vector<std::string> argv, const std::string& run_dir, const std::string& log)
      : Child(std::move(argv), ChildOptions{run_dir, log, -1}) {}
  ~Child() { Stop(); }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  /// Sends `sig` (SIGTERM) and waits; returns the exit code, or -signal. `cpu_s` (optional)
  /// gets the child's user + system CPU time.
  int Stop(int sig = SIGTERM, double* cpu_s = nullptr) {
    if (pid_ <= 0) return 0;
    ::kill(pid_, sig);
    int status = 0;
    rusage ru{};
    ::wait4(pid_, &status, 0, &ru);
    pid_ = -1;
    if (cpu_s)
      *cpu_s = ru.ru_utime.tv_sec + ru.ru_utime.tv_usec * 1e-6 + ru.ru_stime.tv_sec +
               ru.ru_stime.tv_usec * 1e-6;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
  }
  bool Running() const { return pid_ > 0 && ::waitpid(pid_, nullptr, WNOHANG) == 0; }
  pid_t Pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
};

}  // namespace p2i::bench
