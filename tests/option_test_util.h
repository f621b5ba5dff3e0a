/// @file option_test_util.h
/// @brief Checks shared by the tests of the nodes' Options structs (FromParameters + Validate):
/// every declared parameter has a description and its default, and each Validate() rule
/// refuses a bad value with "NODE: PARAMETER must RULE (got VALUE); FIX".
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>

#include "nodes/runtime/parameters.h"

namespace p2i::testing {

using Overrides = std::vector<std::pair<std::string, std::string>>;  ///< KEY, YAML value

/// Options built by Options::FromParameters from `overrides`; `params` (if given) gets the
/// declarations.
template <class Options>
Options OptionsFrom(const Overrides& overrides, runtime::Parameters* params = nullptr) {
  runtime::Parameters local;
  runtime::Parameters& p = params != nullptr ? *params : local;
  for (const auto& [key, value] : overrides) p.SetOverride(key, value);
  return Options::FromParameters(p);
}

/// What Validate() of the options built from `overrides` says, or "" when it accepts them.
template <class Options>
std::string ValidationError(const Overrides& overrides) {
  const Options o = OptionsFrom<Options>(overrides);
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

/// Every parameter declared in `params` (none supplied) has a description and its default.
inline void CheckAllDefaultsDescribed(const runtime::Parameters& params) {
  CHECK_FALSE(params.Declared().empty());
  for (const auto& [name, info] : params.Declared()) {
    INFO(name);
    CHECK_FALSE(info.description.empty());
    CHECK(info.source == "default");
  }
}

/// Options::FromParameters with nothing supplied: declares `count` parameters, each described
/// and at its default, and the defaults pass Validate(). Returns the declarations (for the
/// caller to compare default_text with the struct's field initialisers).
template <class Options>
runtime::Parameters CheckDefaults(size_t count) {
  runtime::Parameters p;
  const Options o = OptionsFrom<Options>({}, &p);
  CHECK(p.Declared().size() == count);
  CheckAllDefaultsDescribed(p);
  CHECK_NOTHROW(o.Validate());
  return p;
}

struct Refusal {
  Overrides overrides;   ///< the bad value (and what it needs around it)
  std::string expected;  ///< part of the message: "PARAMETER must RULE (got VALUE)"
};

/// Each refusal's error starts with "NODE: ", contains `expected`, and says how to fix it.
template <class Options>
void CheckRefusals(const std::string& node, const std::vector<Refusal>& refusals) {
  for (const Refusal& r : refusals) {
    const std::string error = ValidationError<Options>(r.overrides);
    INFO(r.expected << "\n  got: " << error);
    CHECK(error.rfind(node + ": ", 0) == 0);
    CHECK(error.find(r.expected) != std::string::npos);
    CHECK(error.find("); ") != std::string::npos);  // followed by how to fix it
  }
}

}  // namespace p2i::testing
