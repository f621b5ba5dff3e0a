/// @file json_number.h
/// @brief A measurement in JSON: a number when it is finite, null when it is missing (NaN or
/// inf), never a made-up 0.
#pragma once

#include <cmath>

#include <nlohmann/json.hpp>

namespace p2i::util {

inline nlohmann::json NumberOrNull(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

}  // namespace p2i::util
