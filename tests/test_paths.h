/// @file test_paths.h
/// @brief Where tests find the source tree, the build tree and ../shared (weights, real data).
#pragma once

#include <cstdlib>
#include <string>

namespace p2i::testing {

inline std::string SourceDir() { return P2I_SOURCE_DIR; }
inline std::string BinaryDir() { return P2I_BINARY_DIR; }
inline std::string BinDir() { return std::string(P2I_BINARY_DIR) + "/bin"; }

/// ../shared beside the project, or $P2I_SHARED_DIR when set.
inline std::string SharedDir() {
  const char* env = std::getenv("P2I_SHARED_DIR");
  return env != nullptr ? std::string(env) : std::string(P2I_SHARED_DIR_DEFAULT);
}

}  // namespace p2i::testing
