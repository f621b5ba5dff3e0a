/// @file temp_dir.h
/// @brief Temporary folders for tests, the one implementation: a folder removed at the end of
/// the test (TempDir) and one kept for inspection (FreshDir).
#pragma once

#include <stdlib.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace p2i::testing {

/// A new empty folder $TMPDIR/p2i_<tag>_XXXXXX (unique: mkdtemp), removed with everything in it
/// by the destructor. Thread-compatible.
class TempDir {
 public:
  explicit TempDir(const std::string& tag = "test") {
    std::string templ =
        (std::filesystem::temp_directory_path() / ("p2i_" + tag + "_XXXXXX")).string();
    if (mkdtemp(templ.data()) == nullptr) {
      throw std::runtime_error("TempDir: cannot create " + templ);
    }
    path_ = templ;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::string& path() const { return path_; }
  /// path() + "/" + name.
  std::string operator/(const std::string& name) const { return path_ + "/" + name; }
  /// Writes `text` to path()/name (creating sub-folders); returns the file's path.
  std::string Write(const std::string& name, const std::string& text) const {
    const std::filesystem::path p = std::filesystem::path(path_) / name;
    std::filesystem::create_directories(p.parent_path());
    std::ofstream(p) << text;
    return p.string();
  }

 private:
  std::string path_;
};

/// An empty folder $TMPDIR/p2i_<tag>_<pid> (emptied if it exists) that stays after the test, so
/// that its logs and checkpoints can be read when a test fails; for tests whose outputs are
/// large or read by other processes, remove it at the end of the test.
inline std::string FreshDir(const std::string& tag) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("p2i_" + tag + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

}  // namespace p2i::testing
