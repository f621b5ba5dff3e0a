/// @file read_file.h
/// @brief The whole content of a file as a string, for tests that check what a program wrote
/// (empty when the file cannot be opened: the test's own assertions then fail on the content).
#pragma once

#include <fstream>
#include <sstream>
#include <string>

namespace p2i::testing {

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace p2i::testing
