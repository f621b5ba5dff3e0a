/// @file launch_runner.cc
/// @brief fork/exec of node processes, a poll() loop over their output pipes and a self-pipe
/// for signals, respawn timers and the SIGTERM -> SIGKILL stop sequence.
#include "tools/launch_runner.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <memory>
#include <stdexcept>

namespace p2i::tools {
namespace {

using Clock = std::chrono::steady_clock;

// Written by the signal handler, read by the loop: the self-pipe trick keeps the handler
// async-signal-safe and lets poll() wake up for signals and output alike.
int g_signal_pipe[2] = {-1, -1};

void OnSignal(int sig) {
  const int saved = errno;
  const unsigned char byte = static_cast<unsigned char>(sig);
  if (::write(g_signal_pipe[1], &byte, 1) < 0) {
    // Pipe full: a wake-up is already pending, nothing is lost.
  }
  errno = saved;
}

void WriteAll(int fd, const std::string& text) {
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;  // the terminal went away; nothing sensible to do
    done += static_cast<size_t>(n);
  }
}

void Say(const std::string& text) { WriteAll(STDERR_FILENO, "[launch] " + text + "\n"); }

std::string FormatSeconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g s", s);
  return buf;
}

struct Stream {
  int fd = -1;
  size_t proc = 0;
  bool is_err = false;
  std::string partial;
};

struct Proc {
  enum class State { kIdle, kRunning, kWaitRespawn, kDone };
  const ProcessSpec* spec = nullptr;
  State state = State::kIdle;
  pid_t pid = -1;
  bool stop_sent = false;
  bool kill_sent = false;
  Clock::time_point respawn_at;
  int log_fd = -1;
};

class Loop {
 public:
  Loop(const std::vector<ProcessSpec>& specs, const LaunchRunnerOptions& options,
       std::vector<int>* start_counts)
      : options_(options), start_counts_(start_counts) {
    for (const auto& s : specs) {
      Proc p;
      p.spec = &s;
      procs_.push_back(p);
    }
    start_counts_->assign(specs.size(), 0);
  }

  ~Loop() {
    for (auto& s : streams_) ::close(s.fd);
    for (auto& p : procs_) {
      if (p.log_fd >= 0) ::close(p.log_fd);
    }
  }

  int Run() {
    for (size_t i = 0; i < procs_.size(); ++i) Start(i);
    while (!AllDone()) {
      const int timeout_ms = NextTimeoutMs();
      std::vector<pollfd> fds;
      fds.push_back({g_signal_pipe[0], POLLIN, 0});
      for (const auto& s : streams_) fds.push_back({s.fd, POLLIN, 0});
      const int n = ::poll(fds.data(), fds.size(), timeout_ms);
      if (n < 0 && errno != EINTR) throw std::runtime_error(std::string("poll: ") + strerror(errno));
      if (n > 0 && (fds[0].revents & POLLIN)) HandleSignals();
      // Read output before reaping so a process's last lines come before its exit message.
      std::vector<int> ready;
      for (size_t i = 1; i < fds.size(); ++i) {
        if (fds[i].revents != 0) ready.push_back(fds[i].fd);
      }
      for (int fd : ready) ReadStream(fd);
      Reap();
      Timers();
    }
    // Pipes of finished processes may still hold output (or be held open by grandchildren).
    while (!streams_.empty()) ReadStream(streams_.front().fd, /*final=*/true);
    return failed_ ? 1 : 0;
  }

 private:
  bool AllDone() const {
    return std::all_of(procs_.begin(), procs_.end(),
                       [](const Proc& p) { return p.state == Proc::State::kDone; });
  }

  int NextTimeoutMs() const {
    // A bounded wait also re-checks children in case SIGCHLD raced with poll().
    Clock::time_point next = Clock::now() + std::chrono::milliseconds(200);
    for (const auto& p : procs_) {
      if (p.state == Proc::State::kWaitRespawn) next = std::min(next, p.respawn_at);
    }
    if (stopping_ && !kill_sent_) next = std::min(next, kill_deadline_);
    const auto ms =
        std::chrono::duration_cast<std::chrono::milliseconds>(next - Clock::now()).count();
    return static_cast<int>(std::max<long long>(0, ms));
  }

  void Start(size_t index) {
    Proc& p = procs_[index];
    const ProcessSpec& spec = *p.spec;
    int out_pipe[2], err_pipe[2];
    if (::pipe2(out_pipe, O_CLOEXEC) != 0 || ::pipe2(err_pipe, O_CLOEXEC) != 0) {
      throw std::runtime_error(std::string("pipe: ") + strerror(errno));
    }
    if (spec.output != "screen" && p.log_fd < 0) OpenLog(p);
    // Everything the child needs is prepared before fork(): after it only async-signal-safe
    // calls are allowed.
    std::vector<char*> argv;
    for (const auto& a : spec.argv) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    const std::string exec_error = "[launch] cannot execute " + spec.argv[0] + "\n";
    const pid_t parent = ::getpid();
    const pid_t pid = ::fork();
    if (pid < 0) throw std::runtime_error(std::string("fork: ") + strerror(errno));
    if (pid == 0) {
      ::setpgid(0, 0);  // own group: a stop reaches the node's children too
      ::prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (::getppid() != parent) ::_exit(1);  // launcher died before prctl
      for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGCHLD}) ::signal(sig, SIG_DFL);
      sigset_t none;
      sigemptyset(&none);
      ::sigprocmask(SIG_SETMASK, &none, nullptr);
      const int devnull = ::open("/dev/null", O_RDONLY);
      if (devnull >= 0) ::dup2(devnull, STDIN_FILENO);
      ::dup2(out_pipe[1], STDOUT_FILENO);
      ::dup2(err_pipe[1], STDERR_FILENO);
      ::execv(argv[0], argv.data());
      if (::write(STDERR_FILENO, exec_error.data(), exec_error.size()) < 0) {
      }
      ::_exit(127);
    }
    ::setpgid(pid, pid);  // also here, so a stop right after fork finds the group
    ::close(out_pipe[1]);
    ::close(err_pipe[1]);
    for (int fd : {out_pipe[0], err_pipe[0]}) {
      ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
    }
    streams_.push_back({out_pipe[0], index, false, ""});
    streams_.push_back({err_pipe[0], index, true, ""});
    p.pid = pid;
    p.state = Proc::State::kRunning;
    p.stop_sent = p.kill_sent = false;
    ++(*start_counts_)[index];
    Say("[" + spec.name + "] started, pid " + std::to_string(pid));
  }

  void OpenLog(Proc& p) {
    namespace fs = std::filesystem;
    std::error_code ec;
    fs::create_directories(options_.log_dir, ec);
    const std::string path = (fs::path(options_.log_dir) / (p.spec->name + ".log")).string();
    p.log_fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (p.log_fd < 0) {
      throw std::runtime_error("cannot open log file '" + path + "': " + strerror(errno) +
                               " (choose another folder with --log-dir)");
    }
    Say("[" + p.spec->name + "] output goes to " + path);
  }

  void Emit(Stream& s, const std::string& line) {
    const Proc& p = procs_[s.proc];
    const std::string& mode = p.spec->output;
    if (mode != "log") {
      WriteAll(s.is_err ? STDERR_FILENO : STDOUT_FILENO, "[" + p.spec->name + "] " + line + "\n");
    }
    if (mode != "screen" && p.log_fd >= 0) WriteAll(p.log_fd, line + "\n");
  }

  // Reads what is available from one stream; at EOF (or when `final`) flushes and closes it.
  void ReadStream(int fd, bool final = false) {
    auto it = std::find_if(streams_.begin(), streams_.end(),
                           [fd](const Stream& s) { return s.fd == fd; });
    if (it == streams_.end()) return;
    char buf[4096];
    bool eof = false;
    while (true) {
      const ssize_t n = ::read(fd, buf, sizeof(buf));
      if (n > 0) {
        it->partial.append(buf, static_cast<size_t>(n));
        size_t nl;
        while ((nl = it->partial.find('\n')) != std::string::npos) {
          Emit(*it, it->partial.substr(0, nl));
          it->partial.erase(0, nl + 1);
        }
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      eof = (n == 0) || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK);
      break;
    }
    if (eof || final) {
      if (!it->partial.empty()) Emit(*it, it->partial);
      ::close(it->fd);
      streams_.erase(it);
    }
  }

  void DrainProc(size_t index) {
    std::vector<int> fds;
    for (const auto& s : streams_) {
      if (s.proc == index) fds.push_back(s.fd);
    }
    for (int fd : fds) ReadStream(fd);
  }

  void HandleSignals() {
    unsigned char sigs[64];
    const ssize_t n = ::read(g_signal_pipe[0], sigs, sizeof(sigs));
    for (ssize_t i = 0; i < n; ++i) {
      const int sig = sigs[i];
      if (sig == SIGCHLD) continue;  // Reap() runs every iteration
      if (stopping_ && sig == SIGINT) {
        Say("second SIGINT: killing every node now");
        KillRemaining();
      } else {
        BeginStop(std::string("received ") + strsignal(sig));
      }
    }
  }

  void Reap() {
    for (size_t i = 0; i < procs_.size(); ++i) {
      Proc& p = procs_[i];
      if (p.state != Proc::State::kRunning) continue;
      int status = 0;
      const pid_t r = ::waitpid(p.pid, &status, WNOHANG);
      if (r == p.pid) OnExit(i, status);
    }
  }

  void OnExit(size_t index, int status) {
    Proc& p = procs_[index];
    DrainProc(index);
    const std::string& name = p.spec->name;
    bool failed = false;
    std::string how;
    if (WIFEXITED(status)) {
      const int code = WEXITSTATUS(status);
      failed = code != 0;
      how = code == 0 ? "exited cleanly" : "exited with code " + std::to_string(code);
    } else if (WIFSIGNALED(status)) {
      const int sig = WTERMSIG(status);
      const bool ours = p.stop_sent && (sig == SIGTERM || sig == SIGKILL || sig == SIGINT);
      failed = !ours;
      how = std::string("killed by signal ") + std::to_string(sig) + " (" + strsignal(sig) + ")" +
            (ours ? " sent by the launcher" : "");
    }
    if (failed) failed_ = true;
    p.state = Proc::State::kDone;
    p.pid = -1;
    Say("[" + name + "] " + how + (failed ? " -- FAILED" : ""));
    if (stopping_) return;
    if (p.spec->required) {
      BeginStop("required node '" + name + "' exited");
    } else if (p.spec->respawn) {
      p.state = Proc::State::kWaitRespawn;
      p.respawn_at = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(p.spec->respawn_delay));
      Say("[" + name + "] respawning in " + FormatSeconds(p.spec->respawn_delay));
    }
  }

  void Timers() {
    const auto now = Clock::now();
    for (size_t i = 0; i < procs_.size(); ++i) {
      if (procs_[i].state == Proc::State::kWaitRespawn && now >= procs_[i].respawn_at) Start(i);
    }
    if (stopping_ && !kill_sent_ && now >= kill_deadline_) {
      bool any = false;
      for (const auto& p : procs_) any = any || p.state == Proc::State::kRunning;
      if (any) Say("grace period of " + FormatSeconds(options_.grace_period) + " over");
      KillRemaining();
    }
  }

  static void SignalGroup(pid_t pid, int sig) {
    if (::kill(-pid, sig) != 0) ::kill(pid, sig);
  }

  void BeginStop(const std::string& reason) {
    if (stopping_) return;
    stopping_ = true;
    kill_deadline_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(options_.grace_period));
    Say(reason + ": stopping every node (SIGTERM, SIGKILL after " +
        FormatSeconds(options_.grace_period) + ")");
    for (auto& p : procs_) {
      if (p.state == Proc::State::kRunning) {
        SignalGroup(p.pid, SIGTERM);
        p.stop_sent = true;
      } else if (p.state != Proc::State::kDone) {
        p.state = Proc::State::kDone;  // pending respawns and never-started ones are cancelled
      }
    }
  }

  void KillRemaining() {
    kill_sent_ = true;
    for (auto& p : procs_) {
      if (p.state == Proc::State::kRunning && !p.kill_sent) {
        Say("[" + p.spec->name + "] did not stop: SIGKILL");
        SignalGroup(p.pid, SIGKILL);
        p.stop_sent = p.kill_sent = true;
      }
    }
  }

  LaunchRunnerOptions options_;
  std::vector<int>* start_counts_;
  std::vector<Proc> procs_;
  std::vector<Stream> streams_;
  bool stopping_ = false;
  bool kill_sent_ = false;
  bool failed_ = false;
  Clock::time_point kill_deadline_;
};

// Installs the launcher's signal handlers for the lifetime of the object.
class SignalGuard {
 public:
  SignalGuard() {
    if (::pipe2(g_signal_pipe, O_CLOEXEC | O_NONBLOCK) != 0) {
      throw std::runtime_error(std::string("pipe: ") + strerror(errno));
    }
    struct sigaction sa {};
    sa.sa_handler = OnSignal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;
    for (size_t i = 0; i < kSignals.size(); ++i) ::sigaction(kSignals[i], &sa, &old_[i]);
    struct sigaction ignore {};
    ignore.sa_handler = SIG_IGN;
    ::sigaction(SIGPIPE, &ignore, &old_pipe_);
  }
  ~SignalGuard() {
    for (size_t i = 0; i < kSignals.size(); ++i) ::sigaction(kSignals[i], &old_[i], nullptr);
    ::sigaction(SIGPIPE, &old_pipe_, nullptr);
    ::close(g_signal_pipe[0]);
    ::close(g_signal_pipe[1]);
    g_signal_pipe[0] = g_signal_pipe[1] = -1;
  }

 private:
  static constexpr std::array<int, 4> kSignals = {SIGINT, SIGTERM, SIGHUP, SIGCHLD};
  std::array<struct sigaction, 4> old_{};
  struct sigaction old_pipe_ {};
};

}  // namespace

LaunchRunner::LaunchRunner(std::vector<ProcessSpec> specs, LaunchRunnerOptions options)
    : specs_(std::move(specs)), options_(std::move(options)) {
  for (const auto& s : specs_) {
    if (s.argv.empty()) throw std::invalid_argument("LaunchRunner: process '" + s.name + "' has no argv");
  }
}

int LaunchRunner::Run() {
  SignalGuard guard;
  Loop loop(specs_, options_, &start_counts_);
  return loop.Run();
}

}  // namespace p2i::tools
