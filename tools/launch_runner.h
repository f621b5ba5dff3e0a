/// @file launch_runner.h
/// @brief Runs the node processes of a launch: output prefixing, respawn, required nodes,
/// clean stop on SIGINT/SIGTERM (SIGTERM, then SIGKILL after a grace period).
#pragma once

#include <string>
#include <vector>

namespace p2i::tools {

/// One process to run.
struct ProcessSpec {
  std::string name;               ///< prefix of its output lines: "[name] ..."
  std::vector<std::string> argv;  ///< argv[0] is the executable path
  bool respawn = false;
  double respawn_delay = 0.0;     ///< seconds
  bool required = false;          ///< its exit stops the whole launch
  std::string output = "screen";  ///< screen | log | both
};

struct LaunchRunnerOptions {
  double grace_period = 5.0;  ///< seconds between SIGTERM and SIGKILL when stopping
  std::string log_dir;        ///< where output=log|both nodes write <name>.log
};

/// Starts every process (each in its own process group, stdin from /dev/null, stdout/stderr
/// through pipes), forwards their lines prefixed with the node name, respawns `respawn` ones
/// after their delay, and stops everything when a `required` process exits or when the
/// launcher gets SIGINT/SIGTERM/SIGHUP (a second SIGINT kills at once).
///
/// Run() returns 0 when no process failed, 1 otherwise. A failure is an exit code != 0, or
/// death by a signal the runner did not send (a respawned crash still counts). Children get
/// PR_SET_PDEATHSIG so they do not outlive a killed launcher.
///
/// Run() installs process-wide signal handlers for its duration and restores them after:
/// use one runner at a time, from the main thread. Not thread-safe.
class LaunchRunner {
 public:
  LaunchRunner(std::vector<ProcessSpec> specs, LaunchRunnerOptions options);
  int Run();

  /// How many times each process was started (index as in the specs), valid after Run().
  const std::vector<int>& start_counts() const { return start_counts_; }

 private:
  std::vector<ProcessSpec> specs_;
  LaunchRunnerOptions options_;
  std::vector<int> start_counts_;
};

}  // namespace p2i::tools
