/// @file option_error.h
/// @brief The one shape of a refused node option, used by every options struct's Validate():
/// "NODE: PARAMETER must RULE (got VALUE); HOW TO FIX".
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace p2i::runtime {

/// A value as an option error shows it: strings quoted ('gige'), bools true/false, numbers as
/// `operator<<` prints them (0.05, not 0.050000).
template <class T>
std::string ShowOptionValue(const T& value) {
  if constexpr (std::is_same_v<T, bool>) {
    return value ? "true" : "false";
  } else if constexpr (std::is_convertible_v<const T&, std::string>) {
    return "'" + std::string(value) + "'";
  } else {
    std::ostringstream out;
    out << value;
    return out.str();
  }
}

/// Unless `ok`, throws std::invalid_argument("NODE: NAME must RULE (got VALUE); FIX"), which
/// RunNode reports as a configuration error (exit 2). `fix` says what to set instead, e.g.
/// "e.g. rate:=20".
template <class T>
void CheckOption(bool ok, const std::string& node, const std::string& name, const T& value,
                 const std::string& rule, const std::string& fix) {
  if (ok) return;
  throw std::invalid_argument(node + ": " + name + " must " + rule + " (got " +
                              ShowOptionValue(value) + "); " + fix);
}

/// A size given in full or not at all: unless width and height are both > 0 or both 0, throws
/// std::invalid_argument("NODE: width and height must both be > 0 or both 0 (got WxH); FIX").
/// Check each side's range first (CheckOption): this rule says nothing of negative values.
inline void CheckSizePair(const std::string& node, int width, int height, const std::string& fix) {
  if ((width > 0) == (height > 0)) return;
  throw std::invalid_argument(node + ": width and height must both be > 0 or both 0 (got " +
                              std::to_string(width) + "x" + std::to_string(height) + "); " + fix);
}

}  // namespace p2i::runtime
