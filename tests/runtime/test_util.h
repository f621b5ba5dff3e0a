/// @file test_util.h
/// @brief Helpers for runtime tests: a private $P2I_RUN_DIR per test, waiting for conditions.
#pragma once

#include <stdlib.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <functional>
#include <string>
#include <thread>

namespace p2i::runtime::testing {

/// Points $P2I_RUN_DIR at a fresh temporary directory for the lifetime of the object, so
/// default ipc endpoints of one test never meet another test's.
class ScopedRunDir {
 public:
  ScopedRunDir() {
    char tmpl[] = "/tmp/p2i-rt-test-XXXXXX";
    path_ = mkdtemp(tmpl);
    const char* old = std::getenv("P2I_RUN_DIR");
    had_old_ = old != nullptr;
    if (had_old_) old_ = old;
    setenv("P2I_RUN_DIR", path_.c_str(), 1);
  }
  ~ScopedRunDir() {
    if (had_old_) setenv("P2I_RUN_DIR", old_.c_str(), 1); else unsetenv("P2I_RUN_DIR");
    (void)!std::system(("rm -rf '" + path_ + "'").c_str());
  }
  const std::string& Path() const { return path_; }

 private:
  std::string path_, old_;
  bool had_old_ = false;
};

/// Polls `cond` every 5 ms until true or `timeout`; returns its last value.
inline bool WaitUntil(const std::function<bool()>& cond,
                      std::chrono::milliseconds timeout = std::chrono::milliseconds(5000)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (cond()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return cond();
}

}  // namespace p2i::runtime::testing
