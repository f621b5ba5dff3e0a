/// @file launch_error.h
/// @brief The error type of the launch file reader: its message names file, line and key.
#pragma once

#include <stdexcept>
#include <string>

namespace p2i::tools {

/// A launch file that cannot be used as written. what() reads "FILE:LINE: key 'K': problem;
/// how to fix". Thrown only while reading a launch description, never while nodes run.
class LaunchError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace p2i::tools
