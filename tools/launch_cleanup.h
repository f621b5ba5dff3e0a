/// @file launch_cleanup.h
/// @brief Folders a launch leaves in /tmp when it is killed (SIGKILL runs no clean-up): its
/// run dir `/tmp/p2i-$UID/launch-<pid>` and its inline parameter files
/// `/tmp/p2i-launch-params-<pid>-XXXXXX`. The next `p2i launch` removes those whose launcher
/// pid is no longer alive.
#pragma once

#include <string>
#include <vector>

namespace p2i::tools {

/// The folder for one launch's inline parameter files (created, mode 0700):
/// `<tmp>/p2i-launch-params-<pid>-XXXXXX`.
std::string MakeLaunchParamsDir(const std::string& tmp = "/tmp");

/// Removes `<tmp>/p2i-launch-params-<pid>-*` and `<run_root>/launch-<pid>` folders owned by
/// this user whose pid is not a running process. Returns the removed paths. Never throws.
std::vector<std::string> RemoveStaleLaunchDirs(const std::string& run_root,
                                               const std::string& tmp = "/tmp");

}  // namespace p2i::tools
