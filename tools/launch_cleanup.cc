/// @file launch_cleanup.cc
/// @brief Stale launch folders (see launch_cleanup.h).
#include "tools/launch_cleanup.h"

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

namespace p2i::tools {
namespace {

namespace fs = std::filesystem;

// The pid in `name` after `prefix` (digits up to '-' or the end), or -1.
long PidAfter(const std::string& name, const std::string& prefix) {
  if (name.compare(0, prefix.size(), prefix) != 0) return -1;
  size_t i = prefix.size();
  long pid = 0;
  size_t digits = 0;
  while (i < name.size() && name[i] >= '0' && name[i] <= '9' && digits < 9) {
    pid = pid * 10 + (name[i] - '0');
    ++i;
    ++digits;
  }
  if (digits == 0 || (i < name.size() && name[i] != '-')) return -1;
  return pid;
}

bool Alive(long pid) { return ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM; }

bool OwnedByMe(const fs::path& p) {
  struct stat st {};
  return ::lstat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode) && st.st_uid == ::getuid();
}

void Sweep(const std::string& dir, const std::string& prefix, std::vector<std::string>* removed) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const long pid = PidAfter(it->path().filename().string(), prefix);
    if (pid <= 0 || pid == ::getpid() || Alive(pid) || !OwnedByMe(it->path())) continue;
    std::error_code rm;
    fs::remove_all(it->path(), rm);
    if (!rm) removed->push_back(it->path().string());
  }
}

}  // namespace

std::string MakeLaunchParamsDir(const std::string& tmp) {
  std::string templ = tmp + "/p2i-launch-params-" + std::to_string(::getpid()) + "-XXXXXX";
  if (::mkdtemp(templ.data()) == nullptr)
    throw std::runtime_error("cannot create a folder in " + tmp);
  return templ;
}

std::vector<std::string> RemoveStaleLaunchDirs(const std::string& run_root,
                                               const std::string& tmp) {
  std::vector<std::string> removed;
  Sweep(tmp, "p2i-launch-params-", &removed);
  Sweep(run_root, "launch-", &removed);
  return removed;
}

}  // namespace p2i::tools
